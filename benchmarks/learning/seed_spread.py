"""How much does time-to-3 m/s vary between seeds, and between two runs of one seed?

    python -m benchmarks.learning.seed_spread --out OUT                    # Ant, seeds 0 1 2, two runs each, 60 s
    python -m benchmarks.learning.seed_spread --report OUT/seed_spread.json

Each run is ``scripts/train.py --task TASK --seed S --time-limit SECONDS`` in its own process, on a
warm kernel cache (a throwaway first run warms it). On a GPU two runs of one seed differ: CUDA's
atomics sum in no fixed order, so the physics and the gradients differ in the last bits and the
runs drift apart. The CPU gives the same metrics for the same seed (tests/test_reliability.py).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

from benchmarks.harness import ROOT, TRAIN, read_report, write_json  # noqa: E402


def run(out: str, name: str, task: str, seed: int, seconds: float) -> dict:
    run_dir = os.path.join(out, name)
    cmd = [*TRAIN, "--task", task, "--seed", str(seed),
           "--time-limit", str(seconds), "--run-dir", run_dir, "--no-plots"]
    with open(os.path.join(out, f"{name}.log"), "w") as log:
        code = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT,
                               env={**os.environ, "PYTHONUNBUFFERED": "1"})
    row = {"name": name, "seed": seed, "exit_code": code}
    path = os.path.join(run_dir, "summary.json")
    if os.path.isfile(path):
        with open(path) as f:
            s = json.load(f)
        reach = s.get("first_train_speed_3ms") or {}
        row.update({"first_iteration_s": s.get("first_iteration_time_s"), "to_3ms_s": reach.get("time_s"),
                    "to_3ms_samples": reach.get("samples"), "final_speed": (s.get("final") or {}).get("speed"),
                    "samples_per_s": s.get("steady_samples_per_s_median"), "device": s.get("device")})
    print(json.dumps(row), flush=True)
    return row


def summary(rows: list[dict]) -> dict:
    times = [r["to_3ms_s"] for r in rows if r.get("to_3ms_s") is not None]
    same_seed = []
    for seed in sorted({r["seed"] for r in rows}):
        pair = [r["to_3ms_s"] for r in rows if r["seed"] == seed and r.get("to_3ms_s") is not None]
        if len(pair) == 2:
            same_seed.append(abs(pair[0] - pair[1]))
    return {"runs": len(rows), "reached": len(times),
            "to_3ms_s_median": statistics.median(times) if times else None,
            "to_3ms_s_min": min(times, default=None), "to_3ms_s_max": max(times, default=None),
            "to_3ms_s_stdev": statistics.stdev(times) if len(times) > 1 else None,
            "same_seed_abs_difference_s": same_seed}


def report(result: dict) -> str:
    lines = ["| seed | run | first iteration | training episodes at 3 m/s | samples then | speed at the end |",
             "|---:|---:|---:|---:|---:|---:|"]
    for r in result["rows"]:
        t = r.get("to_3ms_s")
        reached = "not reached" if t is None else f"{t:.1f} s"
        samples = "-" if t is None else f"{r['to_3ms_samples'] / 1e6:.1f} M"
        lines.append(f"| {r['seed']} | {r['name'][-1]} | {r.get('first_iteration_s')} s | {reached} | {samples} "
                     f"| {r.get('final_speed') or 0:.2f} m/s |")
    s = result["summary"]
    if s["to_3ms_s_median"] is not None:
        lines.append(f"\nTime to 3 m/s: median {s['to_3ms_s_median']:.1f} s, range {s['to_3ms_s_min']:.1f}-"
                     f"{s['to_3ms_s_max']:.1f} s, standard deviation {s['to_3ms_s_stdev'] or 0:.1f} s over "
                     f"{s['reached']} of {s['runs']} runs; two runs of one seed differed by "
                     + ", ".join(f"{d:.1f}" for d in s["same_seed_abs_difference_s"]) + " s.")
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out")
    ap.add_argument("--task", default="Ant")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--no-warmup", action="store_true", help="skip the throwaway run that warms the kernel cache")
    ap.add_argument("--report", metavar="JSON")
    args = ap.parse_args()
    if args.report:
        print(report(read_report(args.report, "the seed_spread.json of an earlier run")))
        return 0
    if not args.out:
        ap.error("--out OUT is needed to measure (or --report JSON)")
    if args.repeats < 1 or args.seconds <= 0:
        ap.error(f"--repeats {args.repeats} and --seconds {args.seconds}: both must be positive")
    os.makedirs(args.out, exist_ok=True)
    if not args.no_warmup:
        run(args.out, "warmup", args.task, 99, 5)
    rows = [run(args.out, f"seed{seed}_run{k + 1}", args.task, seed, args.seconds)
            for k in range(args.repeats) for seed in args.seeds]
    result = {"command": " ".join(sys.argv), "task": args.task, "seconds": args.seconds, "rows": rows,
              "summary": summary(rows)}
    write_json(os.path.join(args.out, "seed_spread.json"), result)
    print(report(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
