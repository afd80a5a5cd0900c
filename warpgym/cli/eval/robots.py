"""``warpgym eval`` of warpgym's Ant and Humanoid: ``warpgym sim2sim``'s replay in native MuJoCo."""

from __future__ import annotations

from warpgym.cli.eval import refuse_gymnasium_flags


def evaluate(args, ckpt: dict, name: str, device: str, env_args: dict, entry) -> int:
    """A robot's policy, scored as ``warpgym sim2sim`` does: one episode of the trained length in native MuJoCo
    beside warpgym, at the training step and 4x finer; ``--episodes`` x the seeds' count robots, from the first
    seed. The flags that only Gymnasium's env has are refused by name."""
    from warpgym.cli import sim2sim  # noqa: PLC0415

    episode_length = int(env_args.get("max_episode_steps") or entry.episode_length)

    refuse_gymnasium_flags(args, "warpgym's own robots")
    return sim2sim.main([args.checkpoint, "--native-copies", str(args.episodes * len(args.seeds)),
                         "--steps", str(episode_length), "--seed", str(args.seeds[0]), "--device", args.device,
                         *(["--out", args.json] if args.json else [])])
