"""``warpgym eval`` of the legged tasks: native MuJoCo over warpgym.native.legged's fixed schedule of commands,
beside the same episodes in warpgym's env."""

from __future__ import annotations

from warpgym.cli.eval import parser, refuse_gymnasium_flags


def evaluate(args, ckpt: dict, name: str, device: str, env_args: dict, entry) -> int:
    """A legged policy over warpgym.native.legged's schedule of commands, ``--episodes`` x the seeds' count
    episodes in native MuJoCo and in warpgym's env: their tracking errors side by side, and the falls."""
    import torch  # noqa: PLC0415

    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.native.legged import native_episodes, warpgym_episodes  # noqa: PLC0415
    from warpgym.tasks.legged import trained_legged_task  # noqa: PLC0415

    refuse_gymnasium_flags(args, name)
    task = trained_legged_task({**env_args, "task": name})
    spec = ckpt["spec"]
    policy, normalize = policy_from_checkpoint(ckpt, spec["num_obs"], spec["num_actions"], torch.device(device))
    episodes = args.episodes * len(args.seeds)

    @torch.no_grad()
    def batch(obs):
        return policy.act_deterministic(normalize(obs.to(device)))

    @torch.no_grad()
    def one(obs):
        return batch(torch.as_tensor(obs)[None])[0].cpu().numpy()

    if args.level is not None and task.terrain is None:
        parser().error(f"--level {args.level}: {name} walks on flat ground; --level picks the rough tasks' level")
    level = task.max_init_terrain_level if args.level is None else args.level
    native = native_episodes(task, one, episodes, level)
    ours = warpgym_episodes(task, batch, episodes, device, level)
    out = {"task": name, "checkpoint": args.checkpoint, "native": native.to_dict(), "warpgym": ours.to_dict(),
           **({"level": level} if task.terrain is not None else {}),
           "error_xy_ratio": native.error_xy / max(ours.error_xy, 1e-9),
           "error_yaw_ratio": native.error_yaw / max(ours.error_yaw, 1e-9)}
    print(f"{name}, {episodes} episodes of {task.episode_length_s:g} s over a fixed schedule of commands:")
    print("| | tracking error xy [m/s] | yaw [rad/s] | falls |")
    print("|---|---|---|---|")
    for label, t in (("native MuJoCo", native), ("warpgym", ours)):
        print(f"| {label} | {t.error_xy:.3f} | {t.error_yaw:.3f} | {t.falls} of {t.episodes} |")
    print(f"native / warpgym: {out['error_xy_ratio']:.3f} (xy), {out['error_yaw_ratio']:.3f} (yaw)")
    if native.falls_by_kind:  # rough ground: the episodes start on one level, a kind of ground each in turn
        print(f"each kind of ground at level {level}:")
        print("| ground | error xy, native / warpgym | error yaw, native / warpgym | falls, native / warpgym |")
        print("|---|---|---|---|")
        for kind, (fell, n) in native.falls_by_kind.items():
            (nx, ny), (ox, oy) = native.errors_by_kind[kind], ours.errors_by_kind[kind]
            print(f"| {kind} | {nx:.3f} / {ox:.3f} | {ny:.3f} / {oy:.3f} | {fell} / {ours.falls_by_kind[kind][0]} of {n} |")
    if args.json:
        write_json(args.json, out)
    return 0
