"""How long a start takes, and how fast training then runs, with each way of capturing the rollout as
CUDA graphs (agents.collect): one env step's graph replayed horizon_len times ("step"), the whole
rollout as one graph ("rollout"), or none ("off": each step launched from Python).

    python -m benchmarks.speed.rollout_capture --out OUT --tasks Ant-v5 Hopper-v5 Ant --seconds 45 --repeats 3

For each task, one warm-up run fills the kernel cache (not counted); then --repeats rounds, each running
every mode once (the order turning each round, so that a drift of the machine falls on every mode alike).
A run is ``warpgym train --task T --time-limit S --rollout-graph M`` without evaluations. Per run, from
its summary.json: "ready", its first_iteration_time_s (when the first iteration's row was logged, one
iteration late: after the second iteration's captures), and its steady samples/s. Writes
OUT/rollout_capture.json after every run; prints the medians over the rounds and their ratios to "rollout".
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

from benchmarks.harness import ROOT, TRAIN, read_report, read_summary  # noqa: E402

MODES = ("step", "rollout", "off")


def train(task: str, mode: str, seconds: float, run_dir: str, device: str | None) -> dict:
    """One run; its ready time and steady samples/s, or its error."""
    cmd = [*TRAIN, "--task", task, "--time-limit", str(seconds), "--rollout-graph",
           mode, "--config", "eval_gap=1e9", "--run-dir", run_dir, "--no-plots"]
    cmd += ["--device", device] if device else []
    os.makedirs(run_dir, exist_ok=True)
    with open(os.path.join(run_dir, "train.log"), "w") as log:
        code = subprocess.run(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, check=False).returncode
    if code != 0:
        return {"error": f"exit {code}: {run_dir}/train.log"}
    summary = read_summary(run_dir)
    return {"ready_s": summary["first_iteration_time_s"], "samples_per_s": summary["steady_samples_per_s_median"],
            "iterations": summary["iterations"]}


def table(doc: dict) -> str:
    lines = ["| task | rollout graph | ready (s) | steady samples/s | ready / rollout's | samples/s / rollout's |",
             "|---|---|---:|---:|---:|---:|"]
    for task, by_mode in doc["runs"].items():
        med = {}
        for mode, runs in by_mode.items():
            good = [r for r in runs if "error" not in r and r["ready_s"] is not None]
            if good:
                med[mode] = (statistics.median(r["ready_s"] for r in good),
                             statistics.median(r["samples_per_s"] for r in good), len(good))
        for mode, (ready, sps, n) in med.items():
            base = med.get("rollout")
            ratios = (f"{ready / base[0]:.2f} | {sps / base[1]:.3f}" if base else "- | -")
            lines.append(f"| {task} | {mode} ({n} runs) | {ready:.1f} | {sps / 1e6:.3f} M | {ratios} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="folder for the runs and rollout_capture.json")
    ap.add_argument("--report", metavar="JSON", help="print the table of an earlier run's JSON")
    ap.add_argument("--tasks", nargs="+", default=["Ant-v5", "Hopper-v5"])
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=MODES)
    ap.add_argument("--seconds", type=float, default=45.0, help="each run's time limit (default 45)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--device", default=None)
    args = ap.parse_args(argv)
    if args.report:
        print(table(read_report(args.report, "the JSON an earlier --out wrote")))
        return 0
    if not args.out:
        ap.error("--out OUT is required (or --report JSON)")
    if args.repeats < 1 or not args.seconds > 0:
        ap.error(f"--repeats {args.repeats} --seconds {args.seconds}: both must be positive")
    import torch  # noqa: PLC0415

    from warpgym.cli import write_json  # noqa: PLC0415

    gpu = torch.cuda.get_device_name(0) if torch.cuda.is_available() and args.device != "cpu" else "cpu"
    doc = {"meta": {"gpu": gpu, "date": time.strftime("%Y-%m-%d"), "seconds": args.seconds,
                    "command": " ".join(["python -m benchmarks.speed.rollout_capture"] + (argv or sys.argv[1:]))},
           "runs": {task: {mode: [] for mode in args.modes} for task in args.tasks}}
    path = os.path.join(args.out, "rollout_capture.json")
    for task in args.tasks:
        warm = train(task, args.modes[0], min(args.seconds, 30.0), os.path.join(args.out, "runs", f"{task}-warm-up"),
                     args.device)
        if "error" in warm:
            raise SystemExit(f"the warm-up of {task} failed ({warm['error']})")
        for k in range(args.repeats):
            for mode in args.modes[k % len(args.modes):] + args.modes[:k % len(args.modes)]:
                run = train(task, mode, args.seconds, os.path.join(args.out, "runs", f"{task}-{mode}-{k}"), args.device)
                doc["runs"][task][mode].append(run)
                print(task, mode, k, run, flush=True)
                write_json(path, doc)
    print(table(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
