"""Evaluate a trained policy: mean return and mean forward speed of the deterministic policy.

    python scripts/play.py runs/Ant-20261122-120000                 # its checkpoint.pt
    python scripts/play.py runs/Ant-20261122-120000/checkpoint.pt --num-envs 256 --seed 3

Each env plays one full episode with the action mean (no exploration noise).
"""

from __future__ import annotations

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", help="a checkpoint file, or a run directory holding checkpoint.pt")
    ap.add_argument("--num-envs", type=int, default=None, help="episodes to play at once (default 64 GPU, 4 CPU)")
    ap.add_argument("--device", default=None)
    ap.add_argument("--seed", type=int, default=12345)
    args = ap.parse_args(argv)

    import torch  # noqa: PLC0415

    from agents.checkpoint import load, policy_from_checkpoint  # noqa: PLC0415
    from agents.evaluate import evaluate  # noqa: PLC0415
    from warpgym.device import resolve_device  # noqa: PLC0415
    from warpgym.envs import LocomotionVecEnv  # noqa: PLC0415

    path = args.checkpoint
    if os.path.isdir(path):
        path = os.path.join(path, "checkpoint.pt")
    device = resolve_device(args.device)
    ckpt = load(path, torch.device(device))
    cfg = ckpt["config"]
    task = cfg["env_args"]["task"]
    episode_length = cfg["env_args"].get("max_episode_steps")
    n = args.num_envs or (64 if device.startswith("cuda") else 4)
    env = LocomotionVecEnv(task, num_envs=n, device=device, seed=args.seed, max_episode_steps=episode_length)
    policy, normalize = policy_from_checkpoint(ckpt, env.num_obs, env.num_actions, torch.device(device))
    result = evaluate(env, policy, normalize, env.task.episode_length)
    result = {"task": task, "checkpoint": path, "iteration": ckpt["iteration"], "samples": ckpt["samples"],
              "episodes": n, **result}
    print(f"{task}: {n} episodes of the deterministic policy from iteration {ckpt['iteration']}: "
          f"mean return {result['eval/return']:.1f}, mean forward speed {result['eval/speed']:.2f} m/s, "
          f"mean length {result['eval/length']:.0f} steps")
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
