"""Score a policy trained on one of Gymnasium's MuJoCo tasks in Gymnasium's own env, where papers report.

    warpgym eval runs/Hopper-v5-20261125-120000                  # 10 episodes x seeds 0 1 2, on the CPU
    warpgym eval RUN/checkpoint-1200.pt --episodes 20 --seeds 0 --json OUT.json

The checkpoint's deterministic policy (the mean action, its observation normaliser as trained) runs in
``gymnasium.make("<Name>-v5")``: native MuJoCo in float64, the task's constructor arguments and time
limit as trained, the policy's actions in [-1, 1] mapped onto the control ranges as in training. The
same episodes in warpgym's env stand beside them, each world started in the state (and with the first
observation) of one of Gymnasium's episodes, and the ratio of the two mean returns says whether what was
learnt on the GPU holds where it is scored (below 1: worse in Gymnasium's env; for the negative returns
of Reacher and Pusher, warpgym's over Gymnasium's). With the same starts the ratio measures the two
simulators, not the luck of the draw: Reacher's return, for one, is mostly its target's distance.
"""

from __future__ import annotations

import argparse
import json
import sys


def holds(gymnasium_return: float, warpgym_return: float) -> float:
    """How much of warpgym's return holds in Gymnasium's env: their ratio, 1 when equal, below 1 when
    Gymnasium's is worse. For costs (negative returns: Reacher, Pusher) the ratio turns over, so that
    below 1 still means worse."""
    if warpgym_return > 0:
        return gymnasium_return / warpgym_return
    if warpgym_return < 0 and gymnasium_return < 0:
        return warpgym_return / gymnasium_return
    return 1.0 if gymnasium_return >= warpgym_return else 0.0  # signs differ, or warpgym's is 0


def parse_args(argv=None):
    ap = argparse.ArgumentParser(prog="warpgym eval", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", help="a run directory (its checkpoint.pt) or a checkpoint file")
    ap.add_argument("--episodes", type=int, default=10, help="episodes per seed (default 10)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="reset seeds (default 0 1 2)")
    ap.add_argument("--device", default="cpu", help="where the policy and warpgym's env run (default cpu)")
    ap.add_argument("--json", default=None, metavar="OUT", help="also write the result as JSON")
    ap.add_argument("--nudge", type=float, default=0.0, metavar="EPS",
                    help="also play Gymnasium's episodes from starts moved by EPS (e.g. 1e-9) and compare "
                         "Gymnasium with itself: how far a policy's return moves under a change no simulator "
                         "difference is smaller than")
    args = ap.parse_args(argv)
    if not (args.nudge >= 0.0 and args.nudge < 1e-3):
        ap.error(f"--nudge {args.nudge}: a tiny non-negative number, e.g. --nudge 1e-9 (0: not played)")
    if args.episodes < 1:
        ap.error(f"--episodes {args.episodes}: must be a positive integer, e.g. --episodes 10")
    if any(s < 0 for s in args.seeds):
        ap.error(f"--seeds {args.seeds}: seeds are non-negative integers, e.g. --seeds 0 1 2")
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    import numpy as np  # noqa: PLC0415
    import torch  # noqa: PLC0415

    from agents.checkpoint import load_for_command, policy_from_checkpoint  # noqa: PLC0415
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.envs import make_vec_env  # noqa: PLC0415
    from warpgym.envs.conformance import gymnasium_policy_episodes, warpgym_policy_episodes  # noqa: PLC0415
    from warpgym.sim.device import resolve_device  # noqa: PLC0415
    from warpgym.tasks.suite import SUITE  # noqa: PLC0415

    device = resolve_device(args.device)
    path, ckpt = load_for_command(args.checkpoint, torch.device(device))
    env_args = dict(ckpt["config"]["env_args"])
    name = env_args.get("task")
    if name not in SUITE:
        raise SystemExit(f"{path}: its policy was trained on {name}, not one of Gymnasium's tasks ({list(SUITE)}); "
                         "score warpgym's own Ant and Humanoid in native MuJoCo with `warpgym sim2sim`")
    unit = bool(env_args.get("unit_actions", False))
    task = SUITE[name]
    if env_args.get("max_episode_steps"):
        task = task.replace(episode_length=int(env_args["max_episode_steps"]))
    episodes = args.episodes * len(args.seeds)
    env = make_vec_env(name, num_envs=episodes, device=device, seed=args.seeds[0], unit_actions=unit,
                       max_episode_steps=task.episode_length)
    policy, normalize = policy_from_checkpoint(ckpt, env.num_obs, env.num_actions, torch.device(device))

    def act(obs):
        return policy.act_deterministic(normalize(obs.to(device))).cpu()

    per_seed, returns, lengths, starts = [], [], [], []
    for seed in args.seeds:
        r, n = gymnasium_policy_episodes(task, act, args.episodes, seed=1000 * seed, unit_actions=unit, starts=starts)
        per_seed.append({"seed": seed, "return": float(r.mean()), "length": float(n.mean())})
        returns += r.tolist()
        lengths += n.tolist()
    # the same episodes in warpgym: each world starts where one of Gymnasium's episodes started
    ours_r, ours_n = warpgym_policy_episodes(env, lambda obs: policy.act_deterministic(normalize(obs)), starts)
    env.close()
    ours = {"eval/return": float(ours_r.mean()), "eval/length": float(ours_n.mean())}
    gym_return = float(np.mean(returns))
    ratio = holds(gym_return, ours["eval/return"])
    nudged = {}
    if args.nudge:
        moved = np.concatenate([gymnasium_policy_episodes(task, act, args.episodes, seed=1000 * seed, unit_actions=unit,
                                                          nudge=args.nudge)[0] for seed in args.seeds])
        nudged = {"nudge": args.nudge, "gymnasium_nudged_return": float(moved.mean()),
                  "gymnasium_over_gymnasium_nudged": holds(gym_return, float(moved.mean()))}
    result = {"task": name, "checkpoint": path, "iteration": ckpt["iteration"], "samples": ckpt["samples"],
              "episodes": episodes, "gymnasium_return": gym_return, "gymnasium_return_std": float(np.std(returns)),
              "gymnasium_length": float(np.mean(lengths)), "per_seed": per_seed,
              "warpgym_return": ours["eval/return"], "warpgym_length": ours["eval/length"],
              "warpgym_return_std": float(np.std(ours_r)), "same_starts": True,
              "gymnasium_over_warpgym": ratio, **nudged}
    print(f"{name}, policy of iteration {ckpt['iteration']} ({ckpt['samples'] / 1e6:.2f} M samples), deterministic, "
          f"{episodes} episodes each:")
    print(f"  Gymnasium's env (gymnasium.make, float64): return {gym_return:.1f} ± {np.std(returns):.1f}, "
          f"length {np.mean(lengths):.0f}   per seed: "
          + ", ".join(f"{s['seed']}: {s['return']:.1f}" for s in per_seed))
    print(f"  warpgym's env (float32, {device}), the same starts: return {ours['eval/return']:.1f} "
          f"± {np.std(ours_r):.1f}, "
          f"length {ours['eval/length']:.0f}")
    print(f"  held in Gymnasium's env (Gymnasium / warpgym; for costs warpgym / Gymnasium): {ratio:.3f}")
    if nudged:
        print(f"  Gymnasium's env, every start moved by {args.nudge:g}: "
              f"return {nudged['gymnasium_nudged_return']:.1f}; "
              f"Gymnasium / itself so moved: {nudged['gymnasium_over_gymnasium_nudged']:.3f}")
    print(json.dumps(result))
    if args.json:
        write_json(args.json, result)
    return 0


if __name__ == "__main__":
    sys.exit(main())
