"""How many envs per GPU learn fastest? Throughput and memory across sizes, then wall-clock time to
target speeds at the sizes worth training.

    python -m benchmarks.speed.envs_per_gpu --out OUT --task Ant
    python -m benchmarks.speed.envs_per_gpu --out OUT --task Humanoid --target-seeds 0
    python -m benchmarks.speed.envs_per_gpu --report OUT/envs_per_gpu_Humanoid.json OUT2/envs_per_gpu_Humanoid.json \\
        --figure FIG.png                                   # two runs' rows in one table and figure, again
    python -m benchmarks.speed.envs_per_gpu --out OUT --task Ant --envs 16 32 --target-envs 16 32 --batch-size 64 \\
        --throughput-iterations 20 --target-seconds 30 --device cpu               # a smoke run on a CPU

For one task, on one GPU with a warm kernel cache (the first run of the script fills it):
  throughput  for each --envs size: the task env's env-steps/s (`warpgym bench`, median of 3 timings)
              and a training run of --throughput-iterations iterations (at most --throughput-seconds from
              its start): its steady samples/s (the median of its iterations) and peak GPU memory (nvidia-smi, every 0.5 s, the training process alone);
  learning    for each --target-envs size and --target-seeds seed: a --target-seconds training run,
              and when its training episodes first reached each of the task's target speeds (Ant 3
              and 8 m/s, Humanoid 2 and 6 m/s; agents.logger.first_reaching over metrics.jsonl). A run
              ends once it has reached the last one (--keep-going: it trains the whole time).
The mini-batch keeps its size (the task's batch_size), so a larger rollout makes more mini-batch
steps per pass and every sample is learned from as at 4096 envs; --scale-batch scales batch_size
with the envs instead (as many steps per pass as at 4096, each on a larger batch).

Writes OUT/envs_per_gpu_<task>.json after every run (a crash loses nothing measured), the two tables
as OUT/envs_per_gpu_<task>.md (envs per GPU first; time to target: the median over seeds, and how
many seeds got there) and the figure OUT/envs_per_gpu_<task>.png (env-steps/s and samples/s, and
time to each target, against envs). Run directories: OUT/runs/ (no checkpoints are kept).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import statistics
import subprocess
import sys
import threading
import time

from benchmarks.harness import ROOT, read_summary, write_json  # noqa: E402

from benchmarks.targets import TARGETS  # noqa: E402

BASE_ENVS = 4096  # the size the tasks' batch_size was chosen for


class PeakMemory:
    """The most GPU memory [MiB] a process held, polled from nvidia-smi (None without one)."""

    def __init__(self, pid: int, interval: float = 0.5):
        self.pid, self.interval, self.peak = pid, interval, None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        if shutil.which("nvidia-smi"):
            self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.interval):
            try:
                out = subprocess.run(["nvidia-smi", "--query-compute-apps=pid,used_memory", "--format=csv,noheader,nounits"],
                                     capture_output=True, text=True, timeout=10).stdout
            except (OSError, subprocess.SubprocessError):
                continue
            for line in out.splitlines():
                pid, _, mib = line.partition(",")
                if pid.strip() == str(self.pid) and mib.strip().isdigit():
                    self.peak = max(self.peak or 0, int(mib))

    def stop(self) -> int | None:
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()
        return self.peak


class StopAtTargets:
    """Ends a training run (SIGTERM: it finishes its iteration, saves and exits 0) once its training
    episodes have reached every target speed, so a time-to-target run costs the time to its last
    target, not the whole budget; the times it reports are the same either way."""

    def __init__(self, proc: subprocess.Popen, run_dir: str, targets, interval: float = 1.0):
        self.proc, self.run_dir, self.targets, self.interval = proc, run_dir, tuple(targets), interval
        self.fired = False
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def reached(self) -> bool:
        from agents.logger import first_reaching, read_metrics  # noqa: PLC0415

        try:
            rows = read_metrics(self.run_dir)
        except (FileNotFoundError, ValueError):
            return False
        return all(first_reaching(rows, "speed", t) is not None for t in self.targets)

    def _run(self) -> None:
        while not self._stop.wait(self.interval):
            if self.reached():
                if self.proc.poll() is None:
                    self.proc.send_signal(signal.SIGTERM)
                    self.fired = True
                return

    def stop(self) -> bool:
        self._stop.set()
        self._thread.join()
        return self.fired


BATCH: dict[str, int] = {}  # --batch-size: the mini-batch at 4096 envs, instead of the task's preset


def batch_size(task: str, num_envs: int, scale: bool) -> int:
    from warpgym.tasks.presets import PRESETS  # noqa: PLC0415

    base = BATCH.get(task, PRESETS[task]["minibatch_size"])
    return max(1, base * num_envs // BASE_ENVS) if scale else base


def train(task: str, num_envs: int, seconds: float, seed: int, run_dir: str, args, extra=(), stop_at=()) -> dict:
    """One training run in its own process (``extra``: more `warpgym train` flags); its summary,
    metrics, peak GPU memory and whether it ended early because every ``stop_at`` speed was reached."""
    from agents.logger import read_metrics  # noqa: PLC0415

    cmd = [sys.executable, "scripts/train.py", "--task", task, "--num-envs", str(num_envs), "--seed", str(seed),
           "--time-limit", str(seconds), "--run-dir", run_dir, "--no-eval", "--no-plots",
           "--batch-size", str(batch_size(task, num_envs, args.scale_batch)),
           *(["--device", args.device] if args.device else []), *extra]
    os.makedirs(run_dir, exist_ok=True)
    log = os.path.join(run_dir, "train.log")
    with open(log, "w") as f:
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=f, stderr=subprocess.STDOUT)
        memory = PeakMemory(proc.pid)
        stopper = StopAtTargets(proc, run_dir, stop_at) if stop_at else None
        code = proc.wait()
    peak = memory.stop()
    early = stopper.stop() if stopper else False
    if code != 0:
        with open(log) as f:
            raise SystemExit(f"{' '.join(cmd)} failed ({code}):\n{f.read()[-3000:]}")
    summary = read_summary(run_dir)
    return {"summary": summary, "rows": read_metrics(run_dir), "peak_mib": peak, "stopped_at_targets": early}


def env_steps(task: str, num_envs: int, args) -> float | None:
    """The task env's env-steps/s from `warpgym bench --tasks` (median of 3 timings of --bench-steps steps), any
    family's task."""
    out = os.path.join(args.out, "runs", f"bench-{task.replace(':', '_')}-{num_envs}.json")
    cmd = [sys.executable, "-m", "warpgym", "bench", "--tasks", task, "--num-envs", str(num_envs),
           "--steps", str(args.bench_steps), "--repeats", "3", "--out", out,
           *(["--device", args.device] if args.device else [])]
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({done.returncode}):\n{(done.stdout + done.stderr)[-3000:]}")
    with open(out) as f:
        rate = json.load(f)["results"][0]["env_steps_per_s"]
    return statistics.median(rate) if isinstance(rate, list) else rate  # the suite's and legged rows keep each timing


def save(path: str, doc: dict) -> None:
    write_json(path, doc)


def tables(doc: dict) -> str:
    targets = doc["targets"]
    lines = ["| envs per GPU | env-steps/s (task env) | training samples/s | training / env | peak GPU memory | "
             "mini-batch | iterations |", "|---:|---:|---:|---:|---:|---:|---:|"]
    for r in doc["throughput"]:
        ratio = r["samples_per_s"] / r["env_steps_per_s"] if r["samples_per_s"] and r["env_steps_per_s"] else None
        ratio_text = "-" if ratio is None else f"{ratio:.2f}"
        memory = "-" if r["peak_mib"] is None else f"{r['peak_mib'] / 1024:.1f} GiB"
        lines.append(f"| {r['num_envs']} | {fmt_m(r['env_steps_per_s'])} | {fmt_m(r['samples_per_s'])} | "
                     f"{ratio_text} | {memory} | {r['batch_size']} | {r['iterations']} |")
    lines += ["", "| envs per GPU | seeds | " + " | ".join(f"to {t:g} m/s (median; seeds there)" for t in targets)
              + " | samples/s |", "|---:|---:|" + "---:|" * len(targets) + "---:|"]
    for n, cell in learning_by_size(doc).items():
        lines.append(f"| {n} | {cell['seeds']} | " + " | ".join(
            f"{time_text(cell[t]['median_s'])} ({cell[t]['reached']}/{cell['seeds']})" for t in targets)
            + f" | {fmt_m(cell['samples_per_s'])} |")
    return "\n".join(lines)


def time_text(seconds: float | None) -> str:
    return "not reached" if seconds is None else f"{seconds:.0f} s"


def fmt_m(v: float | None) -> str:
    return "-" if v is None else f"{v / 1e6:.2f} M"


def learning_by_size(doc: dict, key: str = "num_envs") -> dict:
    """Per --target-envs size (or other ``key`` of the runs): the median time to each target over the
    seeds that reached it (None if fewer than half did), how many did, and the runs' median samples/s."""
    out = {}
    for n in sorted({r[key] for r in doc["learning"]}):
        runs = [r for r in doc["learning"] if r[key] == n]
        rates = [r["samples_per_s"] for r in runs if r.get("samples_per_s")]
        cell = {"seeds": len(runs), "samples_per_s": statistics.median(rates) if rates else None}
        for t in doc["targets"]:
            times = [r["to_target"][str(t)]["time_s"] for r in runs if r["to_target"].get(str(t))]
            cell[t] = {"reached": len(times),
                       "median_s": statistics.median(times) if len(times) * 2 > len(runs) else None}
        out[n] = cell
    return out


ALIKE = ("task", "device", "targets", "scale_batch")  # what rows of two script runs must share to sit in one table


def merged(paths: list[str]) -> dict:
    """The envs_per_gpu_<task>.json of earlier script runs as one document: the throughput rows of all,
    and the learning runs of all (for example more seeds on the same machine). A ValueError names a file
    that is missing, was run differently, or repeats a size's throughput or a size and seed."""
    doc = None
    for path in paths:
        if not os.path.isfile(path):
            raise ValueError(f"--report {path}: no such file; pass the envs_per_gpu_<task>.json of an earlier run")
        with open(path) as f:
            part = json.load(f)
        if doc is None:
            doc = {**part, "sources": [path]}
            continue
        differ = [k for k in ALIKE if part.get(k) != doc.get(k)]
        if differ:
            raise ValueError(f"--report {path}: made differently from {paths[0]} ({', '.join(differ)}); "
                             "report runs made alike together, the others apart")
        sizes = {r["num_envs"] for r in doc["throughput"]}
        runs = {(r["num_envs"], r["seed"]) for r in doc["learning"]}
        again = [f"throughput at {r['num_envs']}" for r in part["throughput"] if r["num_envs"] in sizes] + \
                [f"{r['num_envs']} envs seed {r['seed']}" for r in part["learning"] if (r["num_envs"], r["seed"]) in runs]
        if again:
            raise ValueError(f"--report {path}: measures again what an earlier file has ({', '.join(again)}); "
                             "pick one of the two")
        doc["throughput"] = sorted(doc["throughput"] + part["throughput"], key=lambda r: r["num_envs"])
        doc["learning"] += part["learning"]
        doc["sources"].append(path)
    return doc


def figure(doc: dict, path: str) -> None:
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
    rows = doc["throughput"]
    if rows:
        n = [r["num_envs"] for r in rows]
        a.plot(n, [(r["env_steps_per_s"] or 0) / 1e6 for r in rows], "o-", label="task env, env-steps/s")
        timed = [r for r in rows if r["samples_per_s"]]
        a.plot([r["num_envs"] for r in timed], [r["samples_per_s"] / 1e6 for r in timed], "s-", label="training, samples/s")
    a.set(xscale="log", xlabel="envs per GPU", ylabel="millions per second", title=f"{doc['task']}: throughput")
    a.set_xticks([r["num_envs"] for r in rows], [str(r["num_envs"]) for r in rows])
    a.legend()
    cells = learning_by_size(doc)
    for i, t in enumerate(doc["targets"]):
        pts = [(n, c[t]["median_s"]) for n, c in cells.items() if c[t]["median_s"] is not None]
        if pts:
            b.plot(*zip(*pts), "o-", color=f"C{i}", label=f"training episodes at {t:g} m/s (median)")
        # every seed that got there, so a target reached by too few seeds for a median still shows
        seeds = [(r["num_envs"], r["to_target"][str(t)]["time_s"]) for r in doc["learning"] if r["to_target"].get(str(t))]
        if seeds:
            b.scatter(*zip(*seeds), s=14, alpha=0.45, color=f"C{i}",
                      label=None if pts else f"training episodes at {t:g} m/s (seeds; too few for a median)")
    b.set(xscale="log", xlabel="envs per GPU", ylabel="seconds from process start", title=f"{doc['task']}: time to target")
    b.set_xticks(list(cells), [str(n) for n in cells])
    for ax in (a, b):
        ax.minorticks_off()  # the log axis's own minor labels overprint the sizes
    if b.lines:
        b.legend()
    fig.suptitle(doc["device"])
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


MIN_ITERATIONS = 20  # a steady median over fewer iterations is mostly graph captures and warm-up


def throughput_row(n: int, steps: float | None, run: dict, args) -> dict:
    """A --envs size's row. A throughput run is --throughput-iterations long, so that every size is timed
    over as many iterations whatever its build and iteration take; if --throughput-seconds (counted from
    the process's start, as every warpgym time limit) cut it to too few, the row has no samples/s and says
    why, rather than a figure of the warm-up."""
    s = run["summary"]
    iterations = s.get("iterations") or 0
    row = {"num_envs": n, "env_steps_per_s": steps, "samples_per_s": s.get("steady_samples_per_s_median"),
           "peak_mib": run["peak_mib"], "batch_size": batch_size(args.task, n, args.scale_batch),
           "iterations": iterations, "phase_s": s.get("steady_phase_s_median")}
    return untimed(row, args.throughput_seconds)


def untimed(row: dict, seconds: float) -> dict:
    """A throughput row without a rate where its run made too few iterations to time, saying why (train_modes.py's
    rows too)."""
    if row["iterations"] < MIN_ITERATIONS:
        row.update(samples_per_s=None, phase_s=None,
                   too_short=f"{row['iterations']} iterations in {seconds:g} s: too few to time; "
                             "raise --throughput-seconds")
    return row


def learning_row(run: dict, task: str, seed: int, seconds: float, **key) -> dict:
    """A learning run's row: when its training episodes first reached each target speed, and its rate.
    ``key``: what tells the run apart (num_envs here, mode in train_modes.py)."""
    from agents.logger import first_reaching  # noqa: PLC0415

    return {**key, "seed": seed, "seconds": seconds,
            "to_target": {str(t): first_reaching(run["rows"], "speed", t) for t in TARGETS[task]},
            "samples_per_s": run["summary"].get("steady_samples_per_s_median"),
            "final": run["summary"].get("final"), "stopped_at_targets": run["stopped_at_targets"]}


def stop_at(args) -> tuple:
    """The speeds at which a learning run may end (none with --keep-going)."""
    return () if args.keep_going else TARGETS[args.task]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="output directory")
    ap.add_argument("--report", nargs="+", metavar="JSON",
                    help="print the tables of earlier runs' envs_per_gpu_<task>.json (several run alike: their rows "
                         "together) and draw the figure again")
    ap.add_argument("--figure", default=None,
                    help="with --report: the figure's path (default: envs_per_gpu_<task>.png beside the first JSON; -: none)")
    ap.add_argument("--task", default="Ant", choices=sorted(TARGETS))
    ap.add_argument("--envs", type=int, nargs="*", default=[2048, 4096, 8192, 16384, 32768],
                    help="sizes for the throughput table (none: skip it)")
    ap.add_argument("--throughput-iterations", type=int, default=60, help="iterations per throughput run")
    ap.add_argument("--throughput-seconds", type=float, default=150.0,
                    help="the most time a throughput run may take, from its process's start")
    ap.add_argument("--bench-steps", type=int, default=100, help="env steps per `warpgym bench` timing")
    ap.add_argument("--target-envs", type=int, nargs="*", default=[4096, 8192, 16384],
                    help="sizes for the time-to-target table (none: skip it)")
    ap.add_argument("--target-seeds", type=int, nargs="+", default=None,
                    help="seeds per size (default: 0 1 2 for the Ant, 0 for the Humanoid)")
    ap.add_argument("--target-seconds", type=float, default=None,
                    help="training time per learning run (default: Ant 180, Humanoid 240)")
    ap.add_argument("--scale-batch", action="store_true", help="scale batch_size with the envs (see above)")
    ap.add_argument("--batch-size", type=int, default=None,
                    help="mini-batch samples (default: the task's preset, 32768; small for a CPU smoke run)")
    ap.add_argument("--keep-going", action="store_true",
                    help="train every learning run for its whole time (default: stop it once it reaches the last target)")
    ap.add_argument("--device", default=None)
    args = ap.parse_args(argv)
    if args.report:
        try:
            doc = merged(args.report)
        except ValueError as e:
            ap.error(str(e))
        rebuilt = " (rebuilt from the tables the run printed, rounded as there)" if doc.get("rebuilt") else ""
        print(f"{doc['device']}, {doc.get('date', 'undated')}: {doc['task']}{rebuilt}\n\n{tables(doc)}")
        if args.figure != "-":
            figure(doc, args.figure or os.path.join(os.path.dirname(args.report[0]), f"envs_per_gpu_{doc['task']}.png"))
        return 0
    if not args.out:
        ap.error("--out OUT is needed to measure (or --report JSON to print the tables of an earlier run)")
    seeds = args.target_seeds if args.target_seeds is not None else ([0, 1, 2] if args.task == "Ant" else [0])
    seconds = args.target_seconds or (180.0 if args.task == "Ant" else 240.0)
    for flag, sizes in (("--envs", args.envs), ("--target-envs", args.target_envs)):
        bad = [n for n in sizes if n < 1]
        if bad:
            ap.error(f"{flag} {bad[0]}: envs per GPU must be positive")
    for flag, v in (("--throughput-seconds", args.throughput_seconds), ("--target-seconds", seconds),
                    ("--throughput-iterations", args.throughput_iterations),
                    ("--bench-steps", args.bench_steps)):
        if not v > 0:
            ap.error(f"{flag} {v}: must be positive")
    if args.throughput_iterations < MIN_ITERATIONS:
        ap.error(f"--throughput-iterations {args.throughput_iterations}: a throughput run needs at least "
                 f"{MIN_ITERATIONS} iterations to time")
    from warpgym.tasks.presets import PRESETS  # noqa: PLC0415

    if args.batch_size is not None:
        if args.batch_size < 1:
            ap.error(f"--batch-size {args.batch_size}: must be positive")
        BATCH[args.task] = args.batch_size
    cfg = PRESETS[args.task]
    for n in sorted(set(args.envs) | set(args.target_envs)):
        samples, size = n * cfg["horizon_len"], batch_size(args.task, n, args.scale_batch)
        if size > samples or samples % size:
            ap.error(f"{n} envs: a rollout of {samples} samples (x horizon_len {cfg['horizon_len']}) does not split into "
                     f"mini-batches of {size}; pick envs per GPU that are multiples of "
                     f"{max(1, size // cfg['horizon_len'])}")

    import torch  # noqa: PLC0415

    from warpgym.sim.device import resolve_device  # noqa: PLC0415

    device = resolve_device(args.device)
    name = torch.cuda.get_device_name(torch.device(device)) if device.startswith("cuda") else "cpu"
    os.makedirs(os.path.join(args.out, "runs"), exist_ok=True)
    path = os.path.join(args.out, f"envs_per_gpu_{args.task}.json")
    doc = {"task": args.task, "device": name, "date": time.strftime("%Y-%m-%d"),
           "targets": list(TARGETS[args.task]), "scale_batch": args.scale_batch,
           "argv": sys.argv[1:] if argv is None else argv, "throughput": [], "learning": []}
    for n in args.envs:
        steps = env_steps(args.task, n, args)
        run = train(args.task, n, args.throughput_seconds, 0, os.path.join(args.out, "runs", f"{args.task}-{n}-tp"), args,
                    ("--max-iterations", str(args.throughput_iterations)))
        doc["throughput"].append(throughput_row(n, steps, run, args))
        save(path, doc)
        row = doc["throughput"][-1]
        print(f"{args.task} x {n}: {fmt_m(steps)} env-steps/s, {fmt_m(row['samples_per_s'])} samples/s, "
              f"peak {run['peak_mib']} MiB" + (f" ({row['too_short']})" if row.get("too_short") else ""), flush=True)
    for n in args.target_envs:
        for seed in seeds:
            run = train(args.task, n, seconds, seed, os.path.join(args.out, "runs", f"{args.task}-{n}-s{seed}"), args,
                        stop_at=stop_at(args))
            doc["learning"].append(learning_row(run, args.task, seed, seconds, num_envs=n))
            save(path, doc)
            print(f"{args.task} x {n} seed {seed}: " + ", ".join(
                f"{t} m/s at {'-' if h is None else round(h['time_s'], 1)} s"
                for t, h in doc["learning"][-1]["to_target"].items()), flush=True)
    text = tables(doc)
    with open(os.path.join(args.out, f"envs_per_gpu_{args.task}.md"), "w") as f:
        f.write(f"{args.task}, {name}\n\n{text}\n")
    figure(doc, os.path.join(args.out, f"envs_per_gpu_{args.task}.png"))
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
