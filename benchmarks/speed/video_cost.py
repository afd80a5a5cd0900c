"""What ``train.py --video`` costs the training iterations: the same run without and with clips.

    python -m benchmarks.speed.video_cost --out bench/video --task Ant --seconds 100 --eval-gap 20

Runs ``scripts/train.py`` twice, one after the other, and writes OUT/video_cost.json: the median
samples/s of the iterations (the iteration clock leaves evaluations out; drawing happens in a
separate process), the median evaluation time, and the clips written.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys

from benchmarks.harness import TRAIN, write_json  # noqa: E402


def measure(run_dir: str) -> dict:
    from agents.logger import read_metrics, steady_median  # noqa: PLC0415

    rows = read_metrics(run_dir)
    evals = [r["eval_s"] for r in rows if "eval_s" in r]
    videos = os.path.join(run_dir, "videos")
    clips = sorted(f for f in os.listdir(videos) if f.endswith(".mp4")) if os.path.isdir(videos) else []
    return {"iterations": len(rows), "samples_per_s": steady_median(rows), "evaluations": len(evals),
            "eval_s": statistics.median(evals) if evals else None, "clips": clips}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--task", default="Ant")
    ap.add_argument("--seconds", type=float, default=100.0)
    ap.add_argument("--eval-gap", type=float, default=20.0)
    args = ap.parse_args(argv)
    if not (args.seconds > 0 and args.eval_gap > 0):
        ap.error(f"--seconds {args.seconds} and --eval-gap {args.eval_gap}: both must be positive")
    os.makedirs(args.out, exist_ok=True)
    result = {"task": args.task, "seconds": args.seconds, "eval_gap": args.eval_gap}
    for name, extra in (("without", []), ("with", ["--video"])):
        run_dir = os.path.join(args.out, name)
        cmd = [*TRAIN, "--task", args.task, "--time-limit", str(args.seconds),
               "--eval-gap", str(args.eval_gap), "--run-dir", run_dir, "--no-plots", "--max-iterations", "1000000",
               *extra]
        with open(os.path.join(args.out, f"{name}.log"), "w") as log:
            rc = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, check=False).returncode
        result[name] = {"rc": rc, **(measure(run_dir) if rc == 0 else {})}
        print(json.dumps({name: result[name]}), flush=True)
    if result["without"].get("samples_per_s") and result["with"].get("samples_per_s"):
        result["ratio_with_to_without"] = result["with"]["samples_per_s"] / result["without"]["samples_per_s"]
    write_json(os.path.join(args.out, "video_cost.json"), result)
    print(json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
