"""Two checkouts' steps side by side on one GPU, each measured by this checkout's harness in a child process with
the other checkout's packages first on the path, in turn in one script run, so that a change's speed is a ratio of
medians taken on one machine minutes apart: the legged tasks by ``benchmarks.speed.step_share`` (the env's step and
warpgym's own share of it against MuJoCo Warp's work on the same worlds), Gymnasium's tasks (``--suite``) by
``warpgym bench --tasks`` and warpgym's robots (``--robots``) by ``warpgym bench --robots`` (their "own share" is
against MuJoCo Warp's loop of that command, on constant controls).

    git archive BASE warpgym kernels agents | tar -x -C /tmp/base
    python -m benchmarks.speed.before_after --before /tmp/base --legged Go1VelocityFlat-v0 G1VelocityFlat-v0 \\
        --num-envs 4096 8192 --out OUT/before_after.json
    python -m benchmarks.speed.before_after --report OUT/before_after.json [MORE.json ...]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

from benchmarks.harness import ROOT, child_env


def median(values) -> float:
    return statistics.median(values) if isinstance(values, list) else float(values)


def run_child(tree: str, module: list[str], out: str):
    """``python -m MODULE ... --out OUT`` with ``tree``'s packages first on the path (its warpgym, kernels and
    agents), this checkout's benchmarks after them."""
    path = os.pathsep.join([tree, ROOT, os.environ.get("PYTHONPATH", "")])
    subprocess.run([sys.executable, "-m", *module, "--out", out], check=True, env=child_env(PYTHONPATH=path),
                   cwd=tree)
    with open(out) as f:
        return json.load(f)


def rows_of(result) -> dict:
    """{(task, envs): (env steps/s, MuJoCo Warp's steps/s)} of a step_share or a ``warpgym bench`` output."""
    out = {}
    for r in result["results"] if isinstance(result, dict) else result:
        out[(r.get("task") or r["robot"], r["num_envs"])] = (median(r["env_steps_per_s"]),
                                                             median(r["mjwarp_steps_per_s"]))
    return out


def table(summary: dict) -> str:
    lines = [f"{summary['gpu']}, {summary['date']}: before {summary['before']}, after {summary['after']}",
             "| task | envs | MuJoCo Warp (M/s) | before (M/s) | own share before | after (M/s) | own share after | "
             "after / before |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for row in summary["rows"]:
        lines.append(f"| {row['task']} | {row['num_envs']} | {row['mjwarp'] / 1e6:.3f} | {row['before'] / 1e6:.3f} | "
                     f"{row['own_before']:.1%} | {row['after'] / 1e6:.3f} | {row['own_after']:.1%} | "
                     f"{row['after'] / row['before']:.3f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.speed.before_after", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--before", help="a checkout (or `git archive`) of the commit to compare against")
    ap.add_argument("--before-name", default="the base commit", help="how the table names it")
    ap.add_argument("--after-name", default="this checkout")
    ap.add_argument("--legged", nargs="*", default=["Go1VelocityFlat-v0", "G1VelocityFlat-v0"])
    ap.add_argument("--suite", nargs="*", default=[], help="Gymnasium's tasks too (Hopper-v5 ...)")
    ap.add_argument("--num-envs", nargs="+", type=int, default=[4096, 8192])
    ap.add_argument("--suite-envs", type=int, default=32768)
    ap.add_argument("--robots", nargs="*", default=[], help="warpgym's Ant and Humanoid too (ant, humanoid)")
    ap.add_argument("--robot-envs", type=int, default=4096)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", help="the summary JSON")
    ap.add_argument("--report", nargs="+", help="print one table of summary JSONs (one GPU, one pair of checkouts) and "
                                               "stop")
    args = ap.parse_args(argv)
    if args.report:
        summaries = []
        for path in args.report:
            with open(path) as f:
                summaries.append(json.load(f))
        print(table({**summaries[0], "rows": [row for s in summaries for row in s["rows"]]}))
        return 0
    if not args.before or not os.path.isdir(os.path.join(args.before, "warpgym")):
        ap.error(f"--before {args.before!r}: give a folder holding the base commit's warpgym/, kernels/ and agents/")
    common = ["--steps", str(args.steps), "--repeats", str(args.repeats)]
    jobs = [["benchmarks.speed.step_share", "--tasks", *args.legged, "--num-envs", *map(str, args.num_envs), *common]] if args.legged else []
    if args.suite:
        jobs.append(["warpgym", "bench", "--tasks", *args.suite, "--num-envs", str(args.suite_envs), *common])
    if args.robots:
        jobs.append(["warpgym", "bench", "--robots", *args.robots, "--num-envs", str(args.robot_envs), *common])
    results = {"before": {}, "after": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for k, module in enumerate(jobs):
            for side, tree in (("before", os.path.abspath(args.before)), ("after", ROOT)):
                results[side].update(rows_of(run_child(tree, module, os.path.join(tmp, f"{side}{k}.json"))))
    import datetime  # noqa: PLC0415

    import torch  # noqa: PLC0415

    gpu = torch.cuda.get_device_name(0) if torch.cuda.is_available() else "cpu"

    rows = []
    for key, (after, mjw) in results["after"].items():
        before, mjw_before = results["before"][key]
        rows.append({"task": key[0], "num_envs": key[1], "before": before, "after": after, "mjwarp": mjw,
                     "mjwarp_before_run": mjw_before, "own_before": 1 - before / mjw_before, "own_after": 1 - after / mjw})
    summary = {"gpu": gpu, "date": datetime.date.today().isoformat(), "before": args.before_name,
               "after": args.after_name, "steps": args.steps, "repeats": args.repeats, "rows": rows}
    print(table(summary))
    if args.out:
        from warpgym.cli import write_json  # noqa: PLC0415

        write_json(args.out, summary)
    return 0


if __name__ == "__main__":
    sys.exit(main())
