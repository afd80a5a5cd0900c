"""A sweep of PPO settings for one of Gymnasium's MuJoCo tasks: the evidence behind its preset.

Every combination of the grid trains for --seconds with each seed (``warpgym train --config ...``),
and its final policy is scored by ``warpgym eval`` in ``gymnasium.make``'s env. The table ranks the
combinations by that return (mean over seeds), beside the training's throughput; the best row is the
candidate preset for agents/config.py.

    python benchmarks/suite_sweep.py --out OUT --task Hopper-v5 --seconds 120 \\
        --grid num_envs=4096,8192 --grid horizon_len=16,32 --grid gamma=0.99,0.995
    python benchmarks/suite_sweep.py --report OUT/sweep-Hopper-v5.json
    python benchmarks/suite_sweep.py --report GPU0/sweep-Hopper-v5.json GPU1/sweep-Hopper-v5.json  # one table

A grid can be split over GPUs (one sweep per GPU, each given part of the grid); ``--report`` joins their
rows, refusing sweeps of another task, budget, seeds or GPU.

Grid names: ``num_envs`` (the command's --num-envs) and any ``Config`` field ``warpgym train --config``
takes (learning_rate, gamma, net_dims as 256x128, reward_scale, normalize_obs, ...).
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)


def parse_grid(texts: list[str]) -> dict[str, list[str]]:
    """``["gamma=0.99,0.995", "net_dims=256x128,64x64"]`` -> {"gamma": ["0.99", "0.995"], "net_dims": ["256,128", ...]}"""
    grid = {}
    for text in texts:
        if "=" not in text:
            raise ValueError(f"--grid {text!r}: write NAME=V1,V2,..., e.g. --grid gamma=0.99,0.995")
        name, values = (s.strip() for s in text.split("=", 1))
        items = [v.strip().replace("x", ",") for v in values.split(",") if v.strip()]
        if not items:
            raise ValueError(f"--grid {text!r}: no values")
        grid[name] = items
    return grid


def command(task: str, combo: dict, seed: int, seconds: float, run_dir: str, device: str | None) -> list[str]:
    cmd = [sys.executable, "-m", "warpgym", "train", "--task", task, "--seed", str(seed), "--time-limit", str(seconds),
           "--run-dir", run_dir, "--no-plots"]
    for name, value in combo.items():
        cmd += ["--num-envs", value] if name == "num_envs" else ["--config", f"{name}={value}"]
    return cmd + (["--device", device] if device else [])


def run_combo(task: str, combo: dict, seeds: list[int], seconds: float, out: str, device: str | None,
              episodes: int) -> dict:
    from warpgym.cli import eval as eval_command  # noqa: PLC0415

    label = " ".join(f"{k}={v}" for k, v in combo.items()) or "preset"
    runs = []
    for seed in seeds:
        run_dir = os.path.join(out, "runs", f"{task}-{len(os.listdir(os.path.join(out, 'runs')))}")
        os.makedirs(run_dir)
        with open(os.path.join(run_dir, "train.log"), "w") as log:
            code = subprocess.run(command(task, combo, seed, seconds, run_dir, device), cwd=ROOT, stdout=log,
                                  stderr=subprocess.STDOUT).returncode
        if code != 0:
            runs.append({"seed": seed, "error": f"exit {code}: {run_dir}/train.log"})
            continue
        summary = json.load(open(os.path.join(run_dir, "summary.json")))
        scored = os.path.join(run_dir, "eval.json")
        eval_command.main([run_dir, "--episodes", str(episodes), "--seeds", "0", "--json", scored]
                          + (["--device", device] if device else []))
        result = json.load(open(scored))
        runs.append({"seed": seed, "run_dir": run_dir, "gymnasium_return": result["gymnasium_return"],
                     "ratio": result["gymnasium_over_warpgym"], "samples": summary["final"]["samples"],
                     "samples_per_s": summary["steady_samples_per_s_median"]})
    good = [r for r in runs if "error" not in r]
    mean = sum(r["gymnasium_return"] for r in good) / len(good) if good else None
    return {"combo": combo, "label": label, "runs": runs, "gymnasium_return": mean}


def table(doc: dict) -> str:
    rows = sorted(doc["rows"], key=lambda r: -(r["gymnasium_return"] if r["gymnasium_return"] is not None else -1e30))
    lines = ["| rank | settings | Gymnasium's env: return (mean of seeds) | per seed | samples/s | lowest ratio |",
             "|---:|---|---:|---|---:|---:|"]
    for i, r in enumerate(rows, 1):
        good = [x for x in r["runs"] if "error" not in x]
        ret = f"{r['gymnasium_return']:.1f}" if r["gymnasium_return"] is not None else "failed"
        seeds = ", ".join(f"{x['gymnasium_return']:.0f}" if "error" not in x else "failed" for x in r["runs"])
        sps = f"{sum(x['samples_per_s'] for x in good) / len(good) / 1e6:.2f} M" if good else "-"
        ratio = f"{min(x['ratio'] for x in good):.3f}" if good else "-"
        lines.append(f"| {i} | {r['label']} | {ret} | {seeds} | {sps} | {ratio} |")
    return "\n".join(lines)


def merged(docs: list[dict]) -> dict:
    """One sweep of several that ran the same task, budget and seeds on the same GPU (their rows together)."""
    keys = ("task", "seconds", "seeds", "gpu")
    kinds = {tuple(json.dumps(d["meta"][k]) for k in keys) for d in docs}
    if len(kinds) > 1:
        raise SystemExit(f"--report: these sweeps differ in {', '.join(keys)} ({sorted(kinds)}); report them apart")
    return {"meta": {**docs[0]["meta"], "dates": sorted({d["meta"]["date"] for d in docs}),
                     "commands": [d["meta"]["command"] for d in docs]},
            "rows": [r for d in docs for r in d["rows"]]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="folder for the runs and sweep-<task>.json")
    ap.add_argument("--report", nargs="+", metavar="JSON")
    ap.add_argument("--task")
    ap.add_argument("--grid", action="append", default=[], metavar="NAME=V1,V2")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="training budget of each run")
    ap.add_argument("--eval-episodes", type=int, default=5)
    ap.add_argument("--device", default=None)
    args = ap.parse_args(argv)
    if args.report:
        docs = []
        for path in args.report:
            with open(path) as f:
                docs.append(json.load(f))
        doc = merged(docs)
        meta = doc["meta"]
        print(f"{meta['task']}, {meta['seconds']:g} s per run, seeds {meta['seeds']}, {meta['gpu']}, "
              f"{', '.join(meta['dates'])}")
        print(table(doc))
        return 0
    if not (args.out and args.task):
        ap.error("--out OUT and --task NAME are required (or --report JSON)")
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.tasks.suite import SUITE  # noqa: PLC0415

    if args.task not in SUITE:
        ap.error(f"--task {args.task!r}: choose from {list(SUITE)}")
    if not args.seconds > 0:
        ap.error(f"--seconds {args.seconds}: must be positive, e.g. --seconds 120")
    try:
        grid = parse_grid(args.grid)
    except ValueError as e:
        ap.error(str(e))
    import torch  # noqa: PLC0415

    os.makedirs(os.path.join(args.out, "runs"), exist_ok=True)
    gpu = torch.cuda.get_device_name(0) if torch.cuda.is_available() and args.device != "cpu" else "cpu"
    doc = {"meta": {"task": args.task, "seconds": args.seconds, "seeds": args.seeds, "grid": grid, "gpu": gpu,
                    "date": time.strftime("%Y-%m-%d"),
                    "command": " ".join(["benchmarks/suite_sweep.py"] + (argv or sys.argv[1:]))}, "rows": []}
    path = os.path.join(args.out, f"sweep-{args.task}.json")
    names = list(grid)
    for values in itertools.product(*(grid[n] for n in names)):
        doc["rows"].append(run_combo(args.task, dict(zip(names, values)), args.seeds, args.seconds, args.out,
                                     args.device, args.eval_episodes))
        print(json.dumps(doc["rows"][-1])[:300], flush=True)
        write_json(path, doc)
    print(table(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
