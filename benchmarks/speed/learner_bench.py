"""Learners side by side on one machine: warpgym's PPO and each adapter (scripts/train_with.py),
the same task, env count and wall-clock budget, one after another in one script run.

    python -m benchmarks.speed.learner_bench --out bench/learners --seconds 120                # all five
    python -m benchmarks.speed.learner_bench --out bench/learners --learners rl_games,sb3       # some
    python -m benchmarks.speed.learner_bench --report bench/learners bench/learners2 --figure docs/figures

Each run writes its run directory under OUT and a row in OUT/learners.json: steady samples/s
(``agents.logger.steady_median``: the first fifth of the iterations left out), the time and samples at which the
training episodes first averaged the task's walking speed (Ant 3 m/s, Humanoid 2 m/s; benchmarks/targets.py),
and the last return and speed. ``--report`` merges the rows of several OUT dirs into one markdown table and
one pair of plots; given a learners.json file (as docs/bench/learners/ keeps them, without the runs), it prints the
rows as that run recorded them.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

from benchmarks.harness import ROOT, TRAIN, write_json  # noqa: E402

from benchmarks.targets import WALKING, walking_row  # noqa: E402

ALL = ("warpgym", "rsl_rl", "skrl", "rl_games", "sb3")
ADAPTERS = {"warpgym": "warpgym's PPO (no adapter)", "rsl_rl": "rsl_rl (`RslRlVecEnv`)", "skrl": "skrl (`SkrlVecEnv`)",
            "rl_games": "rl_games (`RlGamesVecEnv`)", "sb3": "Stable-Baselines3 (`Sb3VecEnv`, numpy)"}


def command(learner: str, task: str, seconds: float, num_envs: int, run_dir: str) -> list[str]:
    common = ["--task", task, "--num-envs", str(num_envs), "--time-limit", str(seconds), "--run-dir", run_dir,
              "--no-plots"]
    if learner == "warpgym":
        return [*TRAIN, *common, "--max-iterations", "1000000"]
    return [sys.executable, os.path.join(ROOT, "scripts", "train_with.py"), learner, *common, "--iterations", "1000000"]


def row_of(learner: str, task: str, run_dir: str, wall_s: float, rc: int) -> dict:
    return {"learner": learner, "run_dir": run_dir, "rc": rc, "wall_s": round(wall_s, 1), **walking_row(run_dir, task)}


def run(args) -> int:
    os.makedirs(args.out, exist_ok=True)
    results = []
    for learner in args.learners:
        run_dir = os.path.join(args.out, learner)
        t0 = time.time()
        with open(os.path.join(args.out, f"{learner}.log"), "w") as log:
            rc = subprocess.run(command(learner, args.task, args.seconds, args.num_envs, run_dir), stdout=log,
                                stderr=subprocess.STDOUT, check=False).returncode
        results.append(row_of(learner, args.task, run_dir, time.time() - t0, rc))
        print(json.dumps(results[-1]), flush=True)
    device = "cpu"
    try:
        import torch  # noqa: PLC0415

        device = torch.cuda.get_device_name(0) if torch.cuda.is_available() else "cpu"
    except ImportError:
        pass
    summary = {"task": args.task, "num_envs": args.num_envs, "seconds": args.seconds, "device": device,
               "date": time.strftime("%Y-%m-%d"), "rows": results}
    write_json(os.path.join(args.out, "learners.json"), summary)
    return 0


def summary_path(out: str) -> str:
    """An OUT dir's learners.json, or a kept learners.json file itself."""
    return out if os.path.isfile(out) else os.path.join(out, "learners.json")


def report(args) -> int:
    rows, meta = [], None
    for out in args.report:
        with open(summary_path(out)) as f:
            data = json.load(f)
        meta = meta or data
        if os.path.isfile(out):  # a kept summary: its rows as recorded (the runs are not kept)
            rows += data["rows"]
            continue
        # recomputed from each run's metrics: the table follows agents.logger's definitions
        rows += [row_of(r["learner"], data["task"], os.path.join(out, r["learner"]), r["wall_s"], r["rc"])
                 for r in data["rows"]]
    print(f"{meta['device']}, {meta['date']}: {meta['task']}, {meta['num_envs']} envs, {meta['seconds']:g} s per "
          "learner from process start, one after another\n")
    print(f"| {meta['task']}: learner | samples/s (median) | first iteration | training episodes reach "
          f"{WALKING[meta['task']]:g} m/s | last return | last speed |")
    print("|---|---:|---:|---:|---:|---:|")

    def fmt(v, spec):
        return "–" if v is None else format(v, spec)

    fastest = max((r.get("samples_per_s") or 0.0 for r in rows), default=0.0)
    for r in rows:
        reach = ("not within the run" if r.get("time_to_target_s") is None
                 else f"{r['time_to_target_s']:.0f} s ({r['samples_to_target'] / 1e6:.1f} M samples)")
        sps = r.get("samples_per_s")
        sps_text = fmt(None if sps is None else sps / 1e6, ".3f") + " M"
        first = r.get("first_row_s", r.get("first_iteration_s"))  # the kept files of 2026-11-24 name it so
        print(f"| {ADAPTERS.get(r['learner'], r['learner'])} | {f'**{sps_text}**' if sps == fastest else sps_text} | "
              f"{fmt(first, '.0f')} s | {reach} | {fmt(r.get('final_return'), '.0f')} | "
              f"{fmt(r.get('final_speed'), '.2f')} m/s |")
    if args.figure:
        from agents.plotting import plot_runs  # noqa: PLC0415

        good = [r for r in rows if r.get("iterations")]
        paths = plot_runs([r["run_dir"] for r in good], args.figure, labels=[r["learner"] for r in good],
                          title=f"warpgym {meta['task']} {meta['num_envs']} envs: learners ({meta['device']})")
        for p in paths:
            os.replace(p, os.path.join(args.figure, f"{meta['task'].lower()}_learners_{os.path.basename(p)}"))
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="directory for the runs and learners.json")
    ap.add_argument("--learners", default=",".join(ALL), help=f"comma-separated, from {', '.join(ALL)}")
    ap.add_argument("--task", default="Ant", choices=sorted(WALKING))
    ap.add_argument("--num-envs", type=int, default=4096)
    ap.add_argument("--seconds", type=float, default=120.0, help="wall-clock budget per learner, from process start")
    ap.add_argument("--report", nargs="+", metavar="OUT",
                    help="print the table of these OUT dirs (or kept learners.json files) instead of running")
    ap.add_argument("--figure", default=None, help="with --report: write the combined plots into this directory")
    args = ap.parse_args(argv)
    if args.report:
        for out in args.report:
            if not os.path.isfile(summary_path(out)):
                ap.error(f"--report {out}: no learners.json there; pass an --out directory of an earlier run or "
                         "a learners.json file")
        return report(args)
    if not args.out:
        ap.error("--out is required to run")
    args.learners = [x.strip() for x in args.learners.split(",") if x.strip()]
    bad = [x for x in args.learners if x not in ALL]
    if bad:
        ap.error(f"--learners: unknown {bad}; choose from {', '.join(ALL)}")
    if args.num_envs < 1 or not args.seconds > 0:
        ap.error("--num-envs and --seconds must be positive")
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
