"""Long runs that must neither produce a NaN nor drift: random actions, then training, at scale.

    python -m benchmarks.reliability.reliability_soak random --task Ant --num-envs 16384 --steps 5e8 --out OUT
    python -m benchmarks.reliability.reliability_soak train  --task Ant --num-envs 16384 --steps 5e8 --out OUT
    python -m benchmarks.reliability.reliability_soak --report OUT/soak_*.json

``random``: ``env.step`` with uniform random actions in [-1, 1] for STEPS env-steps. On the device,
every step: the count of non-finite observation and reward entries. Every WINDOW steps (one host
read): env-steps/s over the window and the GPU memory in use. At the end: the env's fault counters
(diverged resets, NaN actions, solver overflows).

``train``: ``scripts/train.py`` with defaults for STEPS samples; its metrics carry the same fault
counters, the non-finite observation and reward entries of every rollout, samples/s and memory.

Either writes OUT/soak_<mode>_<task>.json with the start and end throughput (medians of the first
and the last tenth of the windows or rows), memory at start and end, and every count.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

from benchmarks.harness import ROOT, TRAIN, write_json  # noqa: E402


def ends(values: list[float]) -> tuple[float | None, float | None]:
    """Medians of the first and the last tenth (at least one value each)."""
    if not values:
        return None, None
    k = max(1, len(values) // 10)
    return statistics.median(values[:k]), statistics.median(values[-k:])


def memory_mib(dev) -> tuple[float, float]:
    """(torch's allocated memory, the device's used memory) in MiB; zeros on the CPU."""
    import torch  # noqa: PLC0415

    if dev.type != "cuda":
        return 0.0, 0.0
    torch.cuda.synchronize(dev)
    free, total = torch.cuda.mem_get_info(dev)
    return torch.cuda.memory_allocated(dev) / 2**20, (total - free) / 2**20


def soak_random(args) -> dict:
    import torch  # noqa: PLC0415

    from warpgym.envs import LocomotionVecEnv  # noqa: PLC0415

    env = LocomotionVecEnv(args.task, num_envs=args.num_envs, device=args.device, seed=args.seed)
    dev = torch.device(env.device)
    obs, _ = env.reset(seed=args.seed)
    gen = torch.Generator(device=dev).manual_seed(args.seed)
    actions = torch.empty(env.action_space.shape, device=dev)
    bad = torch.zeros((), dtype=torch.int64, device=dev)
    for _ in range(20):  # graph capture and allocator warm-up before the first window
        env.step(actions.uniform_(-1, 1, generator=gen))
    mem_start = memory_mib(dev)
    steps_per_window = args.window
    total_windows = max(1, int(args.steps // (args.num_envs * steps_per_window)))
    windows = []
    t_run = time.perf_counter()
    for w in range(total_windows):
        t0 = time.perf_counter()
        for _ in range(steps_per_window):
            obs, reward, _, _, _ = env.step(actions.uniform_(-1, 1, generator=gen))
            bad += (~torch.isfinite(obs)).sum() + (~torch.isfinite(reward)).sum()
        allocated, used = memory_mib(dev)  # synchronises: the window's steps are done
        dt = time.perf_counter() - t0
        windows.append({"window": w, "env_steps_per_s": args.num_envs * steps_per_window / dt,
                        "allocated_mib": allocated, "device_used_mib": used})
        if w % max(1, total_windows // 20) == 0:
            print(f"window {w}/{total_windows}: {windows[-1]['env_steps_per_s'] / 1e6:.3f} M env-steps/s, "
                  f"non-finite so far {int(bad)}", flush=True)
    rate = [w["env_steps_per_s"] for w in windows]
    first, last = ends(rate)
    return {
        "mode": "random", "task": args.task, "num_envs": args.num_envs, "device": torch.cuda.get_device_name(dev) if dev.type == "cuda" else "cpu",
        "env_steps": total_windows * steps_per_window * args.num_envs, "seconds": time.perf_counter() - t_run,
        "nonfinite_obs_reward_entries": int(bad),
        "faults": {k: int(v) for k, v in env.fault_counters().items()},
        "env_steps_per_s_start": first, "env_steps_per_s_end": last, "end_over_start": last / first,
        "window_spread": (min(rate) / statistics.median(rate), max(rate) / statistics.median(rate)),
        "allocated_mib_start": mem_start[0], "allocated_mib_end": windows[-1]["allocated_mib"],
        "device_used_mib_start": mem_start[1], "device_used_mib_end": windows[-1]["device_used_mib"],
        "solver_load": env.sim.solver_load(), "windows": windows,
    }


def soak_train(args) -> dict:
    run_dir = os.path.join(args.out, f"train_{args.task}")
    cmd = [*TRAIN, "--task", args.task, "--num-envs",
           str(args.num_envs), "--total-steps", str(int(args.steps)), "--run-dir", run_dir, "--no-plots",
           "--eval-gap", "60", "--seed", str(args.seed)]
    t0 = time.perf_counter()
    with open(os.path.join(args.out, f"train_{args.task}.log"), "w") as log:
        code = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT,
                               env={**os.environ, "PYTHONUNBUFFERED": "1"})
    from agents.logger import read_metrics  # noqa: PLC0415

    rows = read_metrics(run_dir)
    steady = rows[len(rows) // 10 :]  # past the first graph captures and the first evaluation
    rate = [r["samples_per_s"] for r in steady if "eval/return" not in r]
    first, last = ends(rate)
    faults = {k[len("faults/"):]: v for k, v in rows[-1].items() if k.startswith("faults/")} if rows else {}
    mem = [r.get("memory/allocated_mib") for r in steady if r.get("memory/allocated_mib") is not None]
    nonfinite_logs = sum(1 for r in rows for k in ("return", "loss/surrogate", "loss/value")
                         if r.get(k) is not None and r[k] != r[k])
    return {
        "mode": "train", "task": args.task, "num_envs": args.num_envs, "exit_code": code,
        "samples": rows[-1]["samples"] if rows else 0, "iterations": len(rows), "seconds": time.perf_counter() - t0,
        "faults": faults, "nan_in_logged_returns_or_losses": nonfinite_logs,
        "samples_per_s_start": first, "samples_per_s_end": last, "end_over_start": last / first if first else None,
        "allocated_mib_start": mem[0] if mem else None, "allocated_mib_end": mem[-1] if mem else None,
        "allocated_mib_max": max(mem) if mem else None,
        "final": {k: rows[-1].get(k) for k in ("return", "speed", "eval/return", "eval/speed")} if rows else {},
    }


def num(v) -> str:
    return "-" if v is None else f"{v:.0f}"


def report(paths: list[str]) -> str:
    lines = ["| run | env-steps | non-finite obs/reward entries | diverged resets | NaN actions | overflows "
             "| memory start -> end (MiB) | throughput start -> end |", "|---|---:|---:|---:|---:|---:|---|---|"]
    for path in paths:
        with open(path) as f:
            r = json.load(f)
        f_ = r["faults"]
        steps = r.get("env_steps", r.get("samples"))
        nonfinite = r.get("nonfinite_obs_reward_entries", f_.get("nonfinite_obs_rewards"))
        start, end = (r.get("env_steps_per_s_start") or r.get("samples_per_s_start"),
                      r.get("env_steps_per_s_end") or r.get("samples_per_s_end"))
        lines.append(f"| {r['task']} {r['num_envs']}, {r['mode']} | {steps / 1e8:.2f}e8 | {nonfinite} "
                     f"| {f_.get('diverged_resets')} | {f_.get('nan_actions')} | {f_.get('solver_overflows')} "
                     f"| {num(r['allocated_mib_start'])} -> {num(r['allocated_mib_end'])} "
                     f"| {start / 1e6:.3f} M -> {end / 1e6:.3f} M/s ({end / start:.3f}) |")
    return "\n".join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("mode", nargs="?", choices=("random", "train"))
    ap.add_argument("--task", default="Ant")
    ap.add_argument("--num-envs", type=int, default=16384)
    ap.add_argument("--steps", type=float, default=5e8, help="env-steps (random) or samples (train)")
    ap.add_argument("--window", type=int, default=200, help="steps per throughput window (random)")
    ap.add_argument("--device", default="cuda:0")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default="soak_out")
    ap.add_argument("--report", nargs="+", metavar="JSON", help="print the table of earlier runs")
    args = ap.parse_args()
    if args.report:
        missing = [p for p in args.report if not os.path.isfile(p)]
        if missing:
            ap.error(f"--report {' '.join(missing)}: no such file; pass soak_*.json files of earlier runs")
        print(report(args.report))
        return 0
    if args.mode is None:
        ap.error("give a mode (random or train) or --report JSON ...")
    if args.num_envs < 1 or args.steps < 1 or args.window < 1:
        ap.error(f"--num-envs {args.num_envs}, --steps {args.steps:g}, --window {args.window}: all must be positive")
    os.makedirs(args.out, exist_ok=True)
    result = soak_random(args) if args.mode == "random" else soak_train(args)
    path = os.path.join(args.out, f"soak_{args.mode}_{args.task}.json")
    write_json(path, result)
    print(report([path]), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
