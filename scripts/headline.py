"""The headline numbers of one task with its default settings: one training run, then its policies
checked sim-to-sim.

    python scripts/headline.py --out OUT --task Ant --seconds 300

Trains the task (4096 envs, defaults, evaluation every 20 s) for --seconds, keeping a checkpoint
every 250 iterations; then runs scripts/sim2sim.py on the checkpoint of the default run length
(train.py's DEFAULT_ITERATIONS) and on the final one. Writes OUT/headline_<task>.json: first
iteration, when the training episodes first reached 1, 2 and 3 m/s, the evaluation return and speed
last logged by 120 s and by the end, steady samples/s, fault counts, and the two sim2sim tables.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))


def last_eval_by(rows: list[dict], seconds: float) -> dict | None:
    evals = [r for r in rows if "eval/return" in r and r["time_s"] <= seconds]
    if not evals:
        return None
    r = evals[-1]
    return {"time_s": r["time_s"], "samples": r["samples"], "return": r["eval/return"], "speed": r["eval/speed"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--task", default="Ant")
    ap.add_argument("--seconds", type=float, default=300.0)
    ap.add_argument("--default-iterations", type=int, default=None,
                    help="the checkpoint to check as the default run's (default: train.py's GPU default)")
    ap.add_argument("--train-flags", nargs=argparse.REMAINDER, default=[])
    args = ap.parse_args(argv)

    from agents.logger import read_metrics  # noqa: PLC0415
    from scripts.train import DEFAULT_ITERATIONS  # noqa: PLC0415

    os.makedirs(args.out, exist_ok=True)
    run_dir = os.path.join(args.out, args.task)
    with open(os.path.join(args.out, f"{args.task}.train.log"), "w") as log:
        subprocess.run([sys.executable, os.path.join(HERE, "train.py"), "--task", args.task, "--time-limit",
                        str(args.seconds), "--eval-gap", "20", "--keep-checkpoints", "--save-gap", "250",
                        "--run-dir", run_dir, *args.train_flags], stdout=log, stderr=subprocess.STDOUT, check=True)
    with open(os.path.join(run_dir, "summary.json")) as f:
        summary = json.load(f)
    rows = read_metrics(run_dir)
    out = {"task": args.task, "seconds": args.seconds, "flags": args.train_flags,
           **{k: summary.get(k) for k in ("device", "num_envs", "iterations", "steady_samples_per_s_median",
                                          "first_iteration_time_s", "first_train_speed_1ms", "first_train_speed_2ms",
                                          "first_train_speed_3ms", "first_eval_speed_3ms", "faults", "solver_load",
                                          "final")},
           "eval_by_120s": last_eval_by(rows, 120.0), "eval_at_end": last_eval_by(rows, float("inf")), "sim2sim": {}}
    default_iters = args.default_iterations or DEFAULT_ITERATIONS["cuda"][args.task]
    for label, name in (("default_run", f"checkpoint-{default_iters}.pt"), ("final", "checkpoint.pt")):
        path = os.path.join(run_dir, name)
        if not os.path.exists(path):
            out["sim2sim"][label] = {"error": f"{name} was not written (the run ended before iteration {default_iters})"}
            continue
        target = os.path.join(args.out, f"{args.task}_{label}.sim2sim.json")
        with open(os.path.join(args.out, f"{args.task}_{label}.sim2sim.log"), "w") as log:
            subprocess.run([sys.executable, os.path.join(HERE, "sim2sim.py"), path, "--out", target],
                           stdout=log, stderr=subprocess.STDOUT, check=True)
        with open(target) as f:
            out["sim2sim"][label] = json.load(f)
    with open(os.path.join(args.out, f"headline_{args.task}.json"), "w") as f:
        json.dump(out, f, indent=1)
    print(json.dumps({k: v for k, v in out.items() if k != "sim2sim"}, indent=1))
    for label, s in out["sim2sim"].items():
        for r in s.get("rows", []):
            print(label, r["simulator"], r["substeps"], f"{r['forward_speed']:.2f} m/s ratio {r['speed_ratio']:.2f} "
                  f"z {r['torso_height']:.2f} falls {r['falls']}/{r['robots']} air {r['no_foot_contact_share']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
