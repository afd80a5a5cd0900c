"""How long one PPO update takes, per way of running it: the learner alone, no simulator.

    python -m benchmarks.speed.update_speed --out OUT
    python -m benchmarks.speed.update_speed --out OUT --tasks Ant --envs 4096 8192 --repeats 50
    python -m benchmarks.speed.update_speed --out OUT --tasks Ant --envs 16 --batch-size 64 --device cpu   # a smoke run

For each task's preset (network, horizon, mini-batch, passes) at each --envs size, a rollout of random
observations and actions of the task's sizes is learnt from --repeats times per mode, after --warmup
updates that are not timed:
  graph     the default: each mini-batch step captured once as a CUDA graph and replayed
  compiled  Config.compile_update (`--compile-update`): the loss under torch.compile, captured likewise
  eager     no CUDA graph (`--no-cuda-graph`), for scale
An update is timed alone (synchronised before and after; the median of the repeats, in ms), and so is
the first update of each mode: the capture, and for `compiled` the compile. PPO's arithmetic does not
depend on the values it learns from, so random rollouts time it as training does.
Writes OUT/update_speed.json after every mode and prints the table.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

from benchmarks.harness import write_json  # noqa: E402

# (observations, actions) of each task's env (tests/test_benchmark_reports.py checks them against the envs)
SIZES = {"Ant": (60, 8), "Humanoid": (108, 21)}
MODES = {"graph": dict(cuda_graph=True, compile_update=False), "compiled": dict(cuda_graph=True, compile_update=True),
         "eager": dict(cuda_graph=False, compile_update=False)}


def rollout(task: str, num_envs: int, horizon: int, device, seed: int = 0):
    import torch  # noqa: PLC0415

    from agents.storage import RolloutStorage  # noqa: PLC0415

    num_obs, num_actions = SIZES[task]
    s = RolloutStorage(horizon, num_envs, num_obs, num_actions, device)
    g = torch.Generator(device=device).manual_seed(seed)
    for name in ("obs", "actions", "values", "returns", "advantages"):
        t = getattr(s, name)
        t.copy_(torch.randn(t.shape, generator=g, device=device))
    s.means.copy_(s.actions + 0.3 * torch.randn(s.means.shape, generator=g, device=device))
    s.log_probs.copy_(-0.5 * ((s.actions - s.means) ** 2).sum(-1))
    return s


def time_mode(task: str, num_envs: int, mode: str, args, device) -> dict:
    import torch  # noqa: PLC0415

    from agents.actor_critic import ActorCritic  # noqa: PLC0415
    from agents.config import Config  # noqa: PLC0415
    from agents.ppo import PPO  # noqa: PLC0415

    opts = MODES[mode]
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    cfg = Config.from_preset(task_entry(task).preset, compile_update=opts["compile_update"],
                          **({"minibatch_size": args.batch_size} if args.batch_size else {}))
    minibatches = cfg.check_batch(num_envs)
    torch.manual_seed(0)
    if device.type == "cuda":
        torch.backends.cuda.matmul.allow_tf32 = cfg.tf32  # as the runner sets it
    policy = ActorCritic(*SIZES[task], cfg.net_dims, cfg.activation, cfg.init_noise_std).to(device)
    ppo = PPO(policy, cfg, device, cuda_graph=opts["cuda_graph"])
    storage = rollout(task, num_envs, cfg.horizon_len, device)
    log_std = policy.log_std.detach().clone()

    def one() -> float:
        sync(device)
        t0 = time.perf_counter()
        ppo.update(storage, log_std, minibatches)
        sync(device)
        return time.perf_counter() - t0

    first = one()
    for _ in range(args.warmup):
        one()
    times = [one() for _ in range(args.repeats)]
    steps = cfg.repeat_times * minibatches
    median = statistics.median(times)
    return {"task": task, "num_envs": num_envs, "mode": mode, "minibatch_steps": steps, "batch_size": cfg.minibatch_size,
            "first_update_s": first, "update_ms_median": 1e3 * median, "update_ms_all": [1e3 * t for t in times],
            "ms_per_minibatch_step": 1e3 * median / steps}


def sync(device) -> None:
    import torch  # noqa: PLC0415

    if device.type == "cuda":
        torch.cuda.synchronize(device)


def table(doc: dict) -> str:
    lines = [f"PPO update alone on {doc['device']} (median of {doc['repeats']} updates)", "",
             "| task | envs | mode | mini-batch steps | update | per step | of the graph mode's time | first update |",
             "|---|---:|---|---:|---:|---:|---:|---:|"]
    base = {(r["task"], r["num_envs"]): r["update_ms_median"] for r in doc["rows"] if r["mode"] == "graph"}
    for r in doc["rows"]:
        if "error" in r:
            lines.append(f"| {r['task']} | {r['num_envs']} | {r['mode']} | - | failed: {r['error'][:80]} | | | |")
            continue
        ref = base.get((r["task"], r["num_envs"]))
        share = f"{r['update_ms_median'] / ref:.2f}" if ref else "-"
        lines.append(f"| {r['task']} | {r['num_envs']} | {r['mode']} | {r['minibatch_steps']} | "
                     f"{r['update_ms_median']:.2f} ms | {r['ms_per_minibatch_step']:.3f} ms | {share} | "
                     f"{r['first_update_s']:.1f} s |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--tasks", nargs="+", default=sorted(SIZES), choices=sorted(SIZES))
    ap.add_argument("--envs", type=int, nargs="+", default=[4096])
    ap.add_argument("--modes", nargs="+", default=list(MODES), choices=list(MODES))
    ap.add_argument("--repeats", type=int, default=30)
    ap.add_argument("--warmup", type=int, default=5)
    ap.add_argument("--batch-size", type=int, default=None, help="the mini-batch (default: the task's)")
    ap.add_argument("--device", default=None, help="default: cuda when there is one")
    args = ap.parse_args(argv)
    for flag, values in (("--envs", args.envs), ("--repeats", [args.repeats]), ("--batch-size", [args.batch_size or 1])):
        bad = [v for v in values if v < 1]
        if bad:
            ap.error(f"{flag} {bad[0]}: must be a positive integer")
    if args.warmup < 0:
        ap.error(f"--warmup {args.warmup}: must be 0 or more")
    import torch  # noqa: PLC0415

    device = torch.device(args.device or ("cuda" if torch.cuda.is_available() else "cpu"))
    name = torch.cuda.get_device_name(device) if device.type == "cuda" else "cpu"
    os.makedirs(args.out, exist_ok=True)
    path = os.path.join(args.out, "update_speed.json")
    doc = {"device": name, "torch": torch.__version__, "repeats": args.repeats, "warmup": args.warmup,
           "date": time.strftime("%Y-%m-%d"), "argv": sys.argv[1:] if argv is None else argv, "rows": []}
    for task in args.tasks:
        for n in args.envs:
            for mode in args.modes:
                try:
                    doc["rows"].append(time_mode(task, n, mode, args, device))
                except ValueError as e:  # a mini-batch that does not divide this many envs' rollout
                    ap.error(f"--envs {n} for {task}: {e}")
                except RuntimeError as e:  # a mode this machine cannot run (compiled, without Triton)
                    print(f"{task} {n} {mode}: {e}", file=sys.stderr)
                    doc["rows"].append({"task": task, "num_envs": n, "mode": mode, "error": str(e)})
                write_json(path, doc)
    print(table(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
