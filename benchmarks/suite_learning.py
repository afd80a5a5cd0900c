"""Gymnasium's MuJoCo suite trained with each task's preset and scored in Gymnasium's own env.

For every task and seed: ``warpgym train`` for the task's budget (10 minutes for the locomotion tasks,
3 for the four small ones), keeping the policies at the marks (1, 2, 5, 10 minutes; 1, 2, 3), each
then scored by ``warpgym eval`` (10 episodes in ``gymnasium.make``'s env, beside warpgym's own). One JSON
per run (``OUT/<task>-seed<k>.json``); ``--report`` builds one table from several outputs, refusing
runs made on different GPUs or with different budgets.

    python benchmarks/suite_learning.py --out OUT --tasks Hopper-v5 Walker2d-v5 --seeds 0 1
    python benchmarks/suite_learning.py --report OUT OUT2 ...

The reference figures (``REFERENCE``) are Tianshou's MuJoCo benchmark for SAC: the best return, averaged
over 10 seeds, within the first 1 M steps, on gym's v3 tasks (v2 for Reacher and the two pendulums),
from its examples/mujoco README. "Half" is half of the figure, or twice the cost where it is negative.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

REFERENCE = {"Ant-v5": 5850.0, "HalfCheetah-v5": 12139.0, "Hopper-v5": 3542.0, "Walker2d-v5": 5007.0,
             "Swimmer-v5": 44.0, "Humanoid-v5": 5489.0, "Reacher-v5": -2.6, "InvertedPendulum-v5": 1000.0,
             "InvertedDoublePendulum-v5": 9360.0}
SHORT = ("InvertedPendulum-v5", "InvertedDoublePendulum-v5", "Reacher-v5", "Pusher-v5")
MARKS = {"long": (60.0, 120.0, 300.0, 600.0), "short": (60.0, 120.0, 180.0)}


def half(target: float) -> float:
    return target * 0.5 if target > 0 else target * 2.0


def marks_of(task: str, scale: float) -> tuple[float, ...]:
    return tuple(m * scale for m in MARKS["short" if task in SHORT else "long"])


def run_one(task: str, seed: int, out: str, scale: float, device: str | None, eval_episodes: int) -> dict:
    """Train, keep the policies at the marks, score each in Gymnasium's env; the row for the JSON."""
    from agents.logger import first_reaching, read_metrics  # noqa: PLC0415
    from warpgym.cli import eval as eval_command  # noqa: PLC0415

    marks = marks_of(task, scale)
    run_dir = os.path.join(out, "runs", f"{task}-seed{seed}")
    cmd = [sys.executable, "-m", "warpgym", "train", "--task", task, "--seed", str(seed), "--time-limit",
           str(marks[-1]), "--save-at", *[str(m) for m in marks], "--run-dir", run_dir, "--no-plots"]
    if device:
        cmd += ["--device", device]
    os.makedirs(run_dir, exist_ok=True)
    with open(os.path.join(run_dir, "train.log"), "w") as log:
        code = subprocess.run(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT).returncode
    if code != 0:
        return {"task": task, "seed": seed, "error": f"warpgym train exited {code}: see {run_dir}/train.log"}
    summary = json.load(open(os.path.join(run_dir, "summary.json")))
    rows = read_metrics(run_dir)
    scored = []
    for kept in summary.get("kept_checkpoints", []):
        result_path = kept["path"] + ".eval.json"
        eval_command.main([kept["path"], "--episodes", str(eval_episodes), "--seeds", "0", "--json", result_path])
        result = json.load(open(result_path))
        scored.append({"mark_s": kept["mark_s"], "time_s": kept["time_s"], "samples": kept["samples"],
                       "gymnasium_return": result["gymnasium_return"], "warpgym_return": result["warpgym_return"],
                       "gymnasium_over_warpgym": result["gymnasium_over_warpgym"]})
    target = REFERENCE.get(task)
    reach = {}
    if target is not None:
        for name, value in (("target", target), ("half", half(target))):
            hit = first_reaching(rows, "eval/return", value)
            reach[name] = hit
    return {"task": task, "seed": seed, "budget_s": marks[-1], "marks_s": list(marks), "scored": scored,
            "samples": rows[-1]["samples"] if rows else 0, "num_envs": summary.get("num_envs"),
            "samples_per_s": summary.get("steady_samples_per_s_median"), "reference": target,
            "first_eval_reaching": reach, "device": summary.get("device")}


def table(runs: list[dict]) -> str:
    by_task: dict[str, list[dict]] = {}
    for r in runs:
        if "error" not in r:
            by_task.setdefault(r["task"], []).append(r)
    lines = ["| task | seeds | Gymnasium's env: return at each mark (mean of seeds) | reference | minutes to it "
             "(to half) | samples | samples/s | Gymnasium / warpgym, lowest |", "|---|---:|---|---:|---|---:|---:|---:|"]
    for task, rs in by_task.items():
        marks = rs[0]["marks_s"]
        cells = []
        for m in marks:
            vals = [s["gymnasium_return"] for r in rs for s in r["scored"] if abs(s["mark_s"] - m) < 1e-6]
            cells.append(f"{m / 60:g} min: {sum(vals) / len(vals):.0f}" if vals else f"{m / 60:g} min: -")

        def minutes(key):
            hits = [r["first_eval_reaching"].get(key) for r in rs]
            done = [h["time_s"] / 60 for h in hits if h]
            return f"{sum(done) / len(done):.1f} ({len(done)}/{len(rs)})" if done else f"not reached (0/{len(rs)})"

        ref = rs[0]["reference"]
        ratio = min((s["gymnasium_over_warpgym"] for r in rs for s in r["scored"]), default=float("nan"))
        lines.append(f"| {task} | {len(rs)} | {'; '.join(cells)} | {ref if ref is not None else '-'} | "
                     f"{minutes('target') if ref is not None else '-'} ({minutes('half') if ref is not None else '-'}) | "
                     f"{sum(r['samples'] for r in rs) / len(rs) / 1e6:.1f} M | "
                     f"{sum(r['samples_per_s'] or 0 for r in rs) / len(rs) / 1e6:.2f} M | {ratio:.3f} |")
    return "\n".join(lines)


def report(folders: list[str]) -> int:
    runs, made = [], set()
    for folder in folders:
        for path in sorted(glob.glob(os.path.join(folder, "*-seed*.json"))):
            doc = json.load(open(path))
            made.add((doc["meta"]["gpu"], doc["meta"]["scale"]))
            runs.append(doc["run"])
    if len(made) > 1:
        raise SystemExit(f"--report: these runs were made differently ({sorted(made)}: GPU, budget scale); "
                         "report runs of one kind together")
    if not runs:
        raise SystemExit(f"--report: no <task>-seed<k>.json under {folders}")
    gpu, scale = made.pop()
    print(f"{gpu}; budgets x{scale:g}; returns of the deterministic policy in gymnasium.make's env")
    print(table(runs))
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="folder for the runs and their JSON")
    ap.add_argument("--report", nargs="+", metavar="OUT")
    ap.add_argument("--tasks", nargs="+", default=None)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--device", default=None)
    ap.add_argument("--eval-episodes", type=int, default=10)
    ap.add_argument("--scale", type=float, default=1.0,
                    help="budgets and marks times this (a CPU check: --scale 0.1); reports refuse to mix scales")
    args = ap.parse_args(argv)
    if args.report:
        return report(args.report)
    if not args.out:
        ap.error("--out OUT is required (or --report OUT...)")
    if not args.scale > 0 or args.eval_episodes < 1:
        ap.error(f"--scale {args.scale} / --eval-episodes {args.eval_episodes}: both must be positive")
    import torch  # noqa: PLC0415

    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.tasks.suite import SUITE  # noqa: PLC0415

    tasks = args.tasks or list(SUITE)
    unknown = [t for t in tasks if t not in SUITE]
    if unknown:
        ap.error(f"--tasks {unknown}: choose from {list(SUITE)}")
    os.makedirs(args.out, exist_ok=True)
    gpu = torch.cuda.get_device_name(0) if torch.cuda.is_available() and args.device != "cpu" else "cpu"
    for task in tasks:
        for seed in args.seeds:
            run = run_one(task, seed, args.out, args.scale, args.device, args.eval_episodes)
            doc = {"meta": {"gpu": gpu, "scale": args.scale, "date": time.strftime("%Y-%m-%d"),
                            "command": " ".join(["benchmarks/suite_learning.py"] + (argv or sys.argv[1:]))},
                   "run": run}
            path = os.path.join(args.out, f"{task}-seed{seed}.json")
            write_json(path, doc)
            print(json.dumps(run)[:400], flush=True)
    return report([args.out])


if __name__ == "__main__":
    sys.exit(main())
