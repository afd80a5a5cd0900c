"""Which physics setting stops a trained gait from exploiting the integrator, and what does it cost?

    python scripts/physics_candidates.py --out OUT --task Ant --seconds 80 --candidates baseline substeps4
    python scripts/physics_candidates.py --report OUT [OUT2 ...]      # the table again, from the JSON files

For each candidate: train the task (4096 envs, one GPU) for --seconds of wall-clock time with that
setting, then replay the final policy with scripts/sim2sim.py (warpgym at the training step and at 4x
the substeps, native MuJoCo at both). One row per candidate in OUT/candidates.json: steady training
samples/s, trained forward speed (training episodes and warpgym replay), the 4x-substep and native
ratios, torso height, the share of steps with no foot on the ground and the peak joint speed.
docs/tasks.md's table of candidates comes from these files.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))

# name -> train.py flags on top of the task's defaults at the time of the run
CANDIDATES: dict[str, list[str]] = {
    "baseline": [],
    "substeps2": ["--substeps", "2"],
    "substeps3": ["--substeps", "3"],
    "substeps4": ["--substeps", "4"],
    "substeps4_iter4": ["--substeps", "4", "--physics", "solver_iterations=4", "--physics", "ls_iterations=4"],
    "substeps3_iter4": ["--substeps", "3", "--physics", "solver_iterations=4", "--physics", "ls_iterations=4"],
    "iter4": ["--physics", "solver_iterations=4", "--physics", "ls_iterations=4"],
    "armature0.05": ["--physics", "armature=0.05"],
    "armature0.1": ["--physics", "armature=0.1"],
    "joint_speed30": ["--physics", "max_joint_speed=30"],
    "joint_speed100": ["--physics", "max_joint_speed=100"],
    "contact0.04": ["--physics", "contact_timeconst=0.04"],
    "euler": ["--physics", "integrator=euler"],
    "ls2": ["--physics", "ls_iterations=2"],
    "iter3_ls3": ["--physics", "solver_iterations=3", "--physics", "ls_iterations=3"],
    "iter2_ls2": ["--physics", "solver_iterations=2", "--physics", "ls_iterations=2"],
}


def run(cmd: list[str], log: str, timeout: float) -> int:
    with open(log, "w") as f:
        return subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, timeout=timeout).returncode


def one(name: str, args) -> dict:
    run_dir = os.path.join(args.out, "runs", name)
    t0 = time.time()
    train = [sys.executable, os.path.join(HERE, "train.py"), "--task", args.task, "--time-limit", str(args.seconds),
             "--run-dir", run_dir, "--no-plots", "--eval-gap", "1e9", *CANDIDATES[name], *args.train_flags]
    row: dict = {"candidate": name, "flags": " ".join(CANDIDATES[name])}
    rc = run(train, os.path.join(args.out, f"{name}.train.log"), args.seconds + 300)
    if rc != 0:
        return {**row, "error": f"train.py exited {rc}: see {name}.train.log"}
    with open(os.path.join(run_dir, "summary.json")) as f:
        summary = json.load(f)
    s2s_json = os.path.join(args.out, f"{name}.sim2sim.json")
    rc = run([sys.executable, os.path.join(HERE, "sim2sim.py"), run_dir, "--out", s2s_json, "--steps", "1000",
              "--native-copies", str(args.native_copies)], os.path.join(args.out, f"{name}.sim2sim.log"), 900)
    row.update({"seconds": args.seconds, "steady_samples_per_s": summary["steady_samples_per_s_median"],
                "train_speed_final": summary["final"]["speed"], "train_return_final": summary["final"]["return"],
                "iterations": summary["iterations"], "faults": summary.get("faults"), "wall_s": time.time() - t0})
    if rc != 0:
        return {**row, "error": f"sim2sim.py exited {rc}: see {name}.sim2sim.log"}
    with open(s2s_json) as f:
        rows = json.load(f)["rows"]
    by = {(r["simulator"], i % 2): r for i, r in enumerate(rows)}
    train_step, finer = by[("warpgym", 0)], by[("warpgym", 1)]
    row.update({"replay_speed": train_step["forward_speed"], "finer_ratio": finer["speed_ratio"],
                "torso_height": train_step["torso_height"], "no_foot_share": train_step["no_foot_contact_share"],
                "peak_joint_speed": train_step["peak_joint_speed"], "falls": train_step["falls"],
                "finer_falls": finer["falls"], "robots": train_step["robots"]})
    if ("native MuJoCo", 0) in by:
        native = by[("native MuJoCo", 0)]
        row.update({"native_ratio": native["speed_ratio"],
                    "native_finer_ratio": by[("native MuJoCo", 1)]["speed_ratio"],
                    # native MuJoCo sees contacts in every substep, warpgym's observation in the last only
                    "native_no_foot_share": native["no_foot_contact_share"],
                    "native_longest_flight": native.get("longest_airborne_steps")})
    return row


def table(rows: list[dict]) -> str:
    lines = ["| candidate | samples/s | trained speed (replay) | 4x substeps | native | native 4x finer | "
             "torso height | no foot on ground (last substep / any substep, native) | longest flight | "
             "peak joint speed |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        if "error" in r:
            lines.append(f"| {r['candidate']} | {r['error']} |")
            continue
        nat = (f"{r['native_ratio']:.2f} | {r['native_finer_ratio']:.2f}" if "native_ratio" in r else "- | -")
        any_sub = (f"{100 * r['native_no_foot_share']:.0f} %" if r.get("native_no_foot_share") is not None else "-")
        flight = (f"{r['native_longest_flight']:.0f} steps" if r.get("native_longest_flight") is not None else "-")
        lines.append(f"| {r['candidate']} | {r['steady_samples_per_s'] / 1e6:.2f} M | {r['replay_speed']:.1f} m/s | "
                     f"{r['finer_ratio']:.2f} | {nat} | {r['torso_height']:.2f} m | "
                     f"{100 * r['no_foot_share']:.0f} % / {any_sub} | {flight} | {r['peak_joint_speed']:.0f} rad/s |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="output directory")
    ap.add_argument("--task", default="Ant")
    ap.add_argument("--candidates", nargs="+", default=["baseline"], choices=sorted(CANDIDATES))
    ap.add_argument("--seconds", type=float, default=80.0, help="training wall-clock time per candidate")
    ap.add_argument("--native-copies", type=int, default=16)
    ap.add_argument("--train-flags", nargs=argparse.REMAINDER, default=[], help="passed to every train.py run")
    ap.add_argument("--report", nargs="+", metavar="OUT", help="print the table of these output directories (or their candidates.json files)")
    args = ap.parse_args(argv)
    if args.report:
        rows = []
        for out in args.report:
            with open(out if out.endswith(".json") else os.path.join(out, "candidates.json")) as f:
                rows += json.load(f)["rows"]
        print(table(rows))
        return 0
    if not args.out:
        ap.error("--out is required (or --report)")
    if not args.seconds > 0:
        ap.error(f"--seconds={args.seconds}: must be positive")
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for name in args.candidates:
        rows.append(one(name, args))
        print(json.dumps(rows[-1]), flush=True)
        with open(os.path.join(args.out, "candidates.json"), "w") as f:
            json.dump({"task": args.task, "rows": rows}, f, indent=1)
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
