"""Every run ends: short torchrun trainings back to back, and two failures, on G processes of one host.

    python -m benchmarks.reliability.exits --out OUT                          # 20 runs (Ant, Humanoid, ...) of 20 s on 2 GPUs
    python -m benchmarks.reliability.exits --out OUT --runs 10 --failures 3   # 10 runs, each failure 3 times
    python -m benchmarks.reliability.exits --out OUT --runs 4 --device cpu --num-envs 4 --seconds 8
    python -m benchmarks.reliability.exits --report OUT/exits.json
    python -m benchmarks.reliability.exits --report A/exits.json B/exits.json   # two runs' rows in one table

Finished runs: each is ``torchrun --standalone --nproc_per_node=G scripts/train.py --time-limit S``;
the table gives its exit code and the seconds from its last metrics row (metrics.jsonl's last write)
to the moment torchrun exited. Failures: SIGTERM to torchrun during an iteration, and an exception
raised inside one worker's PPO update (tests/fail_worker.py, with ``--no-cuda-graph`` so that the
update runs its Python), and SIGKILL to the worker of rank 1 (a process the kernel's out-of-memory killer
or a lost node ends without a word); each --failures times. For each, the seconds from the event until no
worker process is left, the exit code, and whether the output names ``--resume RUN_DIR``. Targets (issue 23): every finished run
exits with code 0 within 10 s of its last row; every failure stops all processes within 60 s.
Writes OUT/exits.json after each run.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time

from benchmarks.harness import ROOT, child_env, read_report, reported, write_json  # noqa: E402
TRAIN = os.path.join(ROOT, "scripts", "train.py")
FAIL_WORKER = os.path.join(ROOT, "tests", "fail_worker.py")
EXIT_WITHIN_S, STOP_WITHIN_S = 10.0, 60.0
FAILURES = ["sigterm", "exception", "killed-rank"]


def worker_pids(agent_pid: int) -> list[int]:
    """The processes a torchrun agent started (children in /proc)."""
    found = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/stat") as f:
                if int(f.read().rsplit(")", 1)[1].split()[1]) == agent_pid:
                    found.append(int(pid))
        except (OSError, ValueError, IndexError):
            continue
    return found


def rank_pid(workers: list[int], rank: int) -> int | None:
    """The worker whose torchrun environment says RANK=``rank``."""
    for pid in workers:
        try:
            with open(f"/proc/{pid}/environ", "rb") as f:
                env = dict(kv.split(b"=", 1) for kv in f.read().split(b"\0") if b"=" in kv)
        except OSError:
            continue
        if env.get(b"RANK") == str(rank).encode():
            return pid
    return None


def rows_written(run_dir: str) -> int:
    try:
        with open(os.path.join(run_dir, "metrics.jsonl")) as f:
            return sum(1 for _ in f)
    except OSError:
        return 0


class Job:
    def __init__(self, args, name: str, task: str, flags: list[str], script: str = TRAIN, env: dict | None = None):
        self.run_dir = os.path.join(args.out, "runs", name)
        self.log_path = os.path.join(args.out, "runs", f"{name}.log")
        os.makedirs(os.path.dirname(self.run_dir), exist_ok=True)
        cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", f"--nproc_per_node={args.gpus}",
               script, "--task", task, "--run-dir", self.run_dir, "--no-plots", *device_flags(args), *flags]
        self.log = open(self.log_path, "w")
        self.started = time.time()
        self.proc = subprocess.Popen(cmd, cwd=ROOT, stdout=self.log, stderr=subprocess.STDOUT,
                                     env=child_env(OMP_NUM_THREADS="1", **(env or {})), start_new_session=True)

    def output(self) -> str:
        if not self.log.closed:
            self.log.flush()
        with open(self.log_path) as f:
            return f.read()

    def wait_gone(self, since: float, workers: list[int], limit: float) -> float:
        """Seconds from ``since`` until torchrun and every worker have exited (or ``limit``, then kills)."""
        while time.time() - since < limit:
            if self.proc.poll() is not None and not any(os.path.exists(f"/proc/{p}") for p in workers):
                return time.time() - since
            time.sleep(0.1)
        os.killpg(self.proc.pid, signal.SIGKILL)
        self.proc.wait()
        return float("inf")


def device_flags(args) -> list[str]:
    flags = ["--device", args.device] if args.device else []
    return flags + (["--num-envs", str(args.num_envs)] if args.num_envs else [])


def finished_run(args, k: int) -> dict:
    task = args.tasks[k % len(args.tasks)]
    job = Job(args, f"run{k:02d}-{task}", task, ["--time-limit", str(args.seconds), "--eval-gap", "5"])
    code = job.proc.wait(timeout=args.seconds + 600)
    ended = time.time()
    job.log.close()
    metrics = os.path.join(job.run_dir, "metrics.jsonl")
    last_row = os.path.getmtime(metrics) if os.path.exists(metrics) else None
    return {"kind": "finished", "task": task, "exit_code": code, "rows": rows_written(job.run_dir),
            "wall_s": round(ended - job.started, 1),
            "last_row_to_exit_s": None if last_row is None else round(ended - last_row, 2)}


def failure(args, kind: str, name: str) -> dict:
    task = args.tasks[0]
    flags = ["--max-iterations", "1000000", "--save-gap", "3"]
    made = True
    if kind in ("sigterm", "killed-rank"):
        job = Job(args, name, task, flags)
        deadline = time.time() + 600
        while rows_written(job.run_dir) < 6 and job.proc.poll() is None and time.time() < deadline:
            time.sleep(0.1)
        workers = worker_pids(job.proc.pid)
        event = time.time()
        if kind == "sigterm":
            job.proc.send_signal(signal.SIGTERM)  # a cluster's pre-emption reaches torchrun
        else:
            victim = rank_pid(workers, 1)
            made = victim is not None  # no rank 1 found: the row says no failure was made, and does not hold
            if made:
                os.kill(victim, signal.SIGKILL)
    else:
        job = Job(args, name, task, [*flags, "--no-cuda-graph"], script=FAIL_WORKER,
                  env={"FAIL_AT": "1:6", "WARPGYM_PEER_TIMEOUT": "20"})
        deadline = time.time() + 600
        while "planted failure" not in job.output() and job.proc.poll() is None and time.time() < deadline:
            time.sleep(0.1)
        workers = worker_pids(job.proc.pid)
        event = time.time()
    gone = job.wait_gone(event, workers, STOP_WITHIN_S + 30)
    job.log.close()
    return {"kind": kind, "task": task, "made": made, "exit_code": job.proc.returncode, "workers": len(workers),
            "all_stopped_s": None if gone == float("inf") else round(gone, 2),
            "names_resume": f"--resume {job.run_dir}" in job.output(), "rows": rows_written(job.run_dir)}


def holds(row: dict) -> bool:
    if row["kind"] == "finished":
        return row["exit_code"] == 0 and row["last_row_to_exit_s"] is not None and \
            row["last_row_to_exit_s"] < EXIT_WITHIN_S
    return row.get("made", True) and row["all_stopped_s"] is not None and row["all_stopped_s"] < STOP_WITHIN_S and \
        row["names_resume"]


def report(paths: list[str]) -> str:
    """The table of one exits.json, or of several (runs of this script on the same kind of job, e.g. two GPU pairs
    of one host side by side), their rows numbered in turn and each file's machine and date in the heading."""
    parts = [read_report(p, "the exits.json a run of this script wrote") for p in paths]
    heads = list(dict.fromkeys(f"{d['gpus']} processes on {d['device_name']}, {d['date']}" for d in parts))
    runs = f" ({len(parts)} runs of the script)" if len(parts) > 1 else ""
    rows = [r for d in parts for r in d["rows"]]
    lines = ["; ".join(heads) + runs, "",
             "| # | kind | task | exit code | last row to exit | all processes stopped | names --resume | holds |",
             "|---:|---|---|---:|---:|---:|---|---|"]
    for k, r in enumerate(rows, 1):
        last = "-" if r.get("last_row_to_exit_s") is None else f"{r['last_row_to_exit_s']:.1f} s"
        stopped = "-" if r["kind"] == "finished" else (
            "over 60 s" if r["all_stopped_s"] is None else f"{r['all_stopped_s']:.1f} s")
        resume = "-" if r["kind"] == "finished" else ("yes" if r["names_resume"] else "**no**")
        lines.append(f"| {k} | {r['kind']} | {r['task']} | {r['exit_code']} | {last} | {stopped} | {resume} | "
                     f"{'yes' if holds(r) else '**no**'} |")
    finished = [r for r in rows if r["kind"] == "finished"]
    lines += ["", f"{sum(holds(r) for r in finished)} of {len(finished)} finished runs exited with code 0 within "
              f"{EXIT_WITHIN_S:.0f} s of their last row; slowest "
              f"{max((r['last_row_to_exit_s'] or 0) for r in finished):.1f} s." if finished else ""]
    for kind in FAILURES:
        made = [r for r in rows if r["kind"] == kind]
        if made:
            slowest = max((r["all_stopped_s"] or float("inf")) for r in made)
            lines.append(f"{kind}: {sum(holds(r) for r in made)} of {len(made)} stopped every process within "
                         f"{STOP_WITHIN_S:.0f} s naming --resume; slowest {slowest:.1f} s.")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="directory for exits.json and the runs")
    ap.add_argument("--runs", type=int, default=20, help="finished runs (default 20)")
    ap.add_argument("--seconds", type=float, default=20.0, help="--time-limit of each finished run")
    ap.add_argument("--tasks", nargs="+", default=["Ant", "Humanoid"], help="taken in turn")
    ap.add_argument("--gpus", type=int, default=2, help="processes per run (one per GPU)")
    ap.add_argument("--device", default=None, help="default: train.py's (cuda when present)")
    ap.add_argument("--num-envs", type=int, default=None, help="default: train.py's")
    ap.add_argument("--failures", type=int, default=1, help="times each failure is made (default 1)")
    ap.add_argument("--no-failures", action="store_true", help="skip the failures")
    ap.add_argument("--report", metavar="EXITS_JSON", nargs="+",
                    help="print the table of an earlier run (or of several, their rows together) and stop")
    args = ap.parse_args(argv)
    if reported(ap, args, report, "EXITS_JSON"):
        return 0
    if args.runs < 0 or args.gpus < 1 or args.seconds <= 0 or args.failures < 0:
        ap.error(f"--runs {args.runs}, --gpus {args.gpus}, --seconds {args.seconds}, --failures {args.failures}: "
                 "need runs >= 0, gpus >= 1, seconds > 0, failures >= 0")
    if not os.path.isdir("/proc"):
        raise SystemExit("exits.py finds torchrun's workers through /proc: run it on Linux")
    import torch  # noqa: PLC0415

    os.makedirs(args.out, exist_ok=True)
    cuda = torch.cuda.is_available() and args.device in (None, "cuda") or str(args.device).startswith("cuda")
    data = {"argv": sys.argv[1:] if argv is None else argv, "gpus": args.gpus, "date": time.strftime("%Y-%m-%d"),
            "device_name": torch.cuda.get_device_name(0) if cuda else "CPU", "rows": []}
    kinds = ["finished"] * args.runs + ([] if args.no_failures else FAILURES * args.failures)
    for k, kind in enumerate(kinds):
        row = finished_run(args, k) if kind == "finished" else failure(args, kind, f"{kind}{k - args.runs:02d}")
        data["rows"].append(row)
        print(json.dumps(row), flush=True)
        write_json(os.path.join(args.out, "exits.json"), data)
    print(report([os.path.join(args.out, "exits.json")]))
    return 0 if all(holds(r) for r in data["rows"]) else 1


if __name__ == "__main__":
    sys.exit(main())
