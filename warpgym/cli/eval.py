"""Score a trained policy where its task is judged: Gymnasium's own env for Gymnasium's MuJoCo tasks, where
papers report; native MuJoCo for warpgym's Ant and Humanoid (``warpgym sim2sim``'s replay, which this runs) and
for the legged tasks (warpgym.native_legged: a fixed schedule of commands, tracking errors and falls beside the
same episodes in warpgym's env).

    warpgym eval runs/Hopper-v5-20261125-120000                  # 10 episodes x seeds 0 1 2, on the CPU
    warpgym eval RUN/checkpoint-1200.pt --episodes 20 --seeds 0 --json OUT.json
    warpgym eval runs/Ant-20261122-120000    # 30 robots in native MuJoCo, beside warpgym at 1x and 4x substeps

The checkpoint's deterministic policy (the mean action, its observation normaliser as trained) runs in
``gymnasium.make("<Name>-v5")``: native MuJoCo in float64, the task's constructor arguments and time
limit as trained, the policy's actions in [-1, 1] mapped onto the control ranges as in training. The
same episodes in warpgym's env stand beside them, each world started in the state (and with the first
observation) of one of Gymnasium's episodes, and the ratio of the two mean returns says whether what was
learnt on the GPU holds where it is scored (below 1: worse in Gymnasium's env; for the negative returns
of Reacher and Pusher, warpgym's over Gymnasium's). With the same starts the ratio measures the two
simulators, not the luck of the draw: Reacher's return, for one, is mostly its target's distance.
Each reward term's sum (Gymnasium's info entries: forward, control, survival, ...) stands beside the
return in both envs, so that a gap names its term. ``--json`` also keeps each episode's return and length
in both envs, paired, so that a mean's spread can be read episode by episode (a robot that flips or falls
in a few of them).

    warpgym eval RUN --env-version 4      # also in Gymnasium's v4: where most published figures were made

``--env-version 4`` plays the same episodes in Gymnasium's v4 of the task as well (gym's v2/v3
definitions on MuJoCo's bindings: Reacher's distance read before the step, Walker2d's right foot at
friction 0.9, a survival reward on the step that falls), for the seven tasks whose v4 observation holds
v5's, and prints how much of the v5 return holds there.
"""

from __future__ import annotations

import sys

from warpgym.cli.flags import (CommandParser, check_checkpoint, check_device, non_negative_float, non_negative_int,
                               positive_int)


def holds(gymnasium_return: float, warpgym_return: float) -> float:
    """How much of warpgym's return holds in Gymnasium's env: their ratio, 1 when equal, below 1 when
    Gymnasium's is worse. For costs (negative returns: Reacher, Pusher) the ratio turns over, so that
    below 1 still means worse."""
    if warpgym_return > 0:
        return gymnasium_return / warpgym_return
    if warpgym_return < 0 and gymnasium_return < 0:
        return warpgym_return / gymnasium_return
    return 1.0 if gymnasium_return >= warpgym_return else 0.0  # signs differ, or warpgym's is 0


def parser() -> CommandParser:
    ap = CommandParser(prog="warpgym eval", description=__doc__)
    ap.add_argument("checkpoint", help="a run directory (its checkpoint.pt) or a checkpoint file")
    ap.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                    help="a module of your own that registers the run's task (a run of --task MODULE:NAME); a run's "
                         "files never import code themselves")
    ap.add_argument("--episodes", type=positive_int(10), default=10, help="episodes per seed (default 10)")
    ap.add_argument("--seeds", type=non_negative_int(0), nargs="+", default=[0, 1, 2],
                    help="reset seeds (default 0 1 2)")
    ap.add_argument("--device", default="cpu", help="where the policy and warpgym's env run (default cpu)")
    ap.add_argument("--json", default=None, metavar="OUT", help="also write the result as JSON")
    ap.add_argument("--level", type=non_negative_int(2), default=None,
                    help="rough tasks: the terrain level every episode starts on (default the curriculum's highest "
                         "first level, 5)")
    ap.add_argument("--nudge", type=non_negative_float(1e-9), default=0.0, metavar="EPS",
                    help="also play Gymnasium's episodes from starts moved by EPS (e.g. 1e-9) and compare "
                         "Gymnasium with itself: how far a policy's return moves under a change no simulator "
                         "difference is smaller than")
    ap.add_argument("--normalizer-from", default=None, metavar="CKPT",
                    help="play the policy with CKPT's observation statistics instead of its own (a checkpoint of "
                         "the same task): does a decay follow the weights or the normaliser?")
    ap.add_argument("--env-version", choices=("5", "4"), default="5",
                    help="4: also score in Gymnasium's v4 of the task, from the same reset seeds (default 5: v5 only)")
    return ap


def parse_args(argv=None):
    ap = parser()
    args = ap.parse_args(argv)
    check_checkpoint(ap, args.checkpoint)
    check_device(ap, args.device)
    args.env_version = int(args.env_version)
    if args.env_version == 4 and args.nudge:
        ap.error(f"--nudge {args.nudge} with --env-version 4: the nudge compares v5 with itself; run them apart")
    if args.nudge >= 1e-3:
        ap.error(f"--nudge {args.nudge}: a tiny non-negative number, e.g. --nudge 1e-9 (0: not played)")
    return args


def mean_terms(terms: dict[str, list[float]]) -> dict[str, float]:
    return {name: float(sum(v) / len(v)) for name, v in terms.items() if v}


def terms_line(columns: dict[str, dict[str, float]], returns: dict[str, float], lengths: dict[str, float]) -> str:
    """Each reward term's mean episode sum in each env ("a | b"); the rest of the return, where the terms
    do not sum to it (HumanoidStandup's 1 a step), as its own entry."""
    names = list(next(iter(columns.values())))
    cells = [f"{name} " + " | ".join(f"{col[name]:.1f}" if name in col else "-" for col in columns.values())
             for name in names]
    if any(set(col) != set(names) for col in columns.values()):  # v4 names fewer terms: no rest to compare
        return "; ".join(cells)
    rest = {env: returns[env] - sum(col.values()) for env, col in columns.items()}
    if any(abs(r) > 1e-3 * max(1.0, abs(returns[env])) for env, r in rest.items()):
        cells.append("the rest " + " | ".join(f"{rest[env]:.1f} ({rest[env] / lengths[env]:.2f} a step)"
                                              for env in columns))
    return "; ".join(cells)


def gymnasium_side(task, act, episodes: int, seeds: list[int], unit: bool, version: int = 5,
                   starts: list | None = None, nudge: float = 0.0) -> dict:
    """The policy's episodes in ``gymnasium.make`` of the task (v5, or v4): ``episodes`` from reset seed
    1000 s on, for each s of ``seeds`` (``gymnasium_policy_episodes``' starts, nudge and version)."""
    import numpy as np  # noqa: PLC0415

    from warpgym.envs.conformance import gymnasium_policy_episodes  # noqa: PLC0415

    per_seed, returns, lengths, terms = [], [], [], {}
    for seed in seeds:
        r, n = gymnasium_policy_episodes(task, act, episodes, seed=1000 * seed, unit_actions=unit, starts=starts,
                                         nudge=nudge, terms=terms, version=version)
        per_seed.append({"seed": seed, "return": float(r.mean()), "length": float(n.mean())})
        returns += r.tolist()
        lengths += n.tolist()
    return {"return": float(np.mean(returns)), "std": float(np.std(returns)), "length": float(np.mean(lengths)),
            "per_seed": per_seed, "terms": mean_terms(terms), "returns": returns, "lengths": lengths}


def in_native_mujoco(args, ckpt: dict, name: str, device: str, env_args: dict, entry) -> int:
    """A robot's policy, scored as ``warpgym sim2sim`` does: one episode of the trained length in native MuJoCo
    beside warpgym, at the training step and 4x finer; ``--episodes`` x the seeds' count robots, from the first
    seed. The flags that only Gymnasium's env has are refused by name."""
    from warpgym.cli import sim2sim  # noqa: PLC0415

    episode_length = int(env_args.get("max_episode_steps") or entry.episode_length)

    gym_only = [flag for flag, given in (("--nudge", args.nudge), ("--normalizer-from", args.normalizer_from),
                                         ("--env-version 4", args.env_version == 4)) if given]
    if gym_only:
        parser().error(f"{', '.join(gym_only)}: Gymnasium's env only; {args.checkpoint} holds a policy of warpgym's "
                       "own robots, scored in native MuJoCo: drop it")
    return sim2sim.main([args.checkpoint, "--native-copies", str(args.episodes * len(args.seeds)),
                         "--steps", str(episode_length), "--seed", str(args.seeds[0]), "--device", args.device,
                         *(["--out", args.json] if args.json else [])])


def legged_in_native_mujoco(args, ckpt: dict, name: str, device: str, env_args: dict, entry) -> int:
    """A legged policy over warpgym.native_legged's schedule of commands, ``--episodes`` x the seeds' count
    episodes in native MuJoCo and in warpgym's env: their tracking errors side by side, and the falls."""
    import torch  # noqa: PLC0415

    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.native_legged import native_episodes, warpgym_episodes  # noqa: PLC0415
    from warpgym.tasks.legged import get_legged_task  # noqa: PLC0415

    gym_only = [flag for flag, given in (("--nudge", args.nudge), ("--normalizer-from", args.normalizer_from),
                                         ("--env-version 4", args.env_version == 4)) if given]
    if gym_only:
        parser().error(f"{', '.join(gym_only)}: Gymnasium's env only; {args.checkpoint} holds a policy of {name}, "
                       "scored in native MuJoCo: drop it")
    task = get_legged_task(name)
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


def main(argv=None) -> int:
    args = parse_args(argv)
    import torch  # noqa: PLC0415

    from agents.checkpoint import load_for_command, with_normalizer  # noqa: PLC0415
    from warpgym.cli import run_task  # noqa: PLC0415
    from warpgym.sim.device import resolve_device  # noqa: PLC0415

    device = resolve_device(args.device)
    path, ckpt = load_for_command(args.checkpoint, torch.device(device))
    if args.normalizer_from:
        other_path, other = load_for_command(args.normalizer_from, torch.device(device))
        try:
            ckpt = with_normalizer(ckpt, other, (path, other_path))
        except ValueError as e:  # a wrong value, found once the files are read: one line, status 2 as for a flag
            parser().error(f"--normalizer-from {args.normalizer_from}: {e}")
        print(f"the policy of {path} with the observation statistics of {other_path} "
              f"(iteration {other['iteration']})")
    env_args = dict(ckpt["config"]["env_args"])
    name = env_args.get("task")
    try:
        entry = run_task(name, args.imports)
    except ValueError as e:
        parser().error(f"{path}: {e}")
    args.checkpoint_path = path
    if args.normalizer_from:
        args.normalizer_path, args.normalizer_iteration = other_path, other["iteration"]
    return entry.evaluate(args, ckpt, name, device, env_args, entry)


def in_gymnasium(args, ckpt: dict, name: str, device: str, env_args: dict, entry) -> int:
    """A policy of Gymnasium's suite in ``gymnasium.make``'s env (and, from the same starts, in warpgym's)."""
    import numpy as np  # noqa: PLC0415
    import torch  # noqa: PLC0415

    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.envs import make_vec_env  # noqa: PLC0415
    from warpgym.envs.conformance import v4_tasks, warpgym_policy_episodes  # noqa: PLC0415
    from warpgym.tasks.suite import SUITE  # noqa: PLC0415

    path = args.checkpoint_path
    if args.env_version == 4 and SUITE[name].v4_observation is None:
        parser().error(f"--env-version 4: {name}'s v4 observation is not v5's plus entries after it (or v4 needs "
                       f"MuJoCo < 3), so a v5 policy cannot play it; v4 is scored for {v4_tasks()}")
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

    starts = []
    gym = gymnasium_side(task, act, args.episodes, args.seeds, unit, starts=starts)
    # the same episodes in warpgym: each world starts where one of Gymnasium's episodes started
    ours_terms = {}
    ours_r, ours_n = warpgym_policy_episodes(env, lambda obs: policy.act_deterministic(normalize(obs)), starts,
                                             terms=ours_terms)
    env.close()
    ours = {"eval/return": float(ours_r.mean()), "eval/length": float(ours_n.mean())}
    gym_return = gym["return"]
    ratio = holds(gym_return, ours["eval/return"])
    extra = {}
    if args.nudge:
        moved = gymnasium_side(task, act, args.episodes, args.seeds, unit, nudge=args.nudge)["return"]
        extra = {"nudge": args.nudge, "gymnasium_nudged_return": moved,
                 "gymnasium_over_gymnasium_nudged": holds(gym_return, moved)}
    if args.env_version == 4:
        old = gymnasium_side(task, act, args.episodes, args.seeds, unit, version=4)
        extra = {"v4_return": old["return"], "v4_return_std": old["std"], "v4_length": old["length"],
                 "v4_per_seed": old["per_seed"], "v4_terms": old["terms"],
                 "v4_over_v5": holds(old["return"], gym_return)}
    result = {"task": name, "checkpoint": path, "iteration": ckpt["iteration"], "samples": ckpt["samples"],
              "episodes": episodes, "gymnasium_return": gym_return, "gymnasium_return_std": gym["std"],
              "gymnasium_length": gym["length"], "per_seed": gym["per_seed"], "gymnasium_terms": gym["terms"],
              "warpgym_return": ours["eval/return"], "warpgym_length": ours["eval/length"],
              "warpgym_return_std": float(np.std(ours_r)), "warpgym_terms": mean_terms(ours_terms),
              "same_starts": True, "gymnasium_over_warpgym": ratio,
              # episode by episode, paired (the same start in both envs): a mean hides a knife edge, a robot that
              # falls or flips in a few episodes
              "gymnasium_returns": gym["returns"], "gymnasium_lengths": gym["lengths"],
              "warpgym_returns": ours_r.tolist(), "warpgym_lengths": ours_n.tolist(), **extra}
    if args.normalizer_from:
        result.update(normalizer_from=args.normalizer_path, normalizer_iteration=args.normalizer_iteration)
    if ckpt["config"].get("normalize_obs"):  # the statistics the policy was played with: where do they drift?
        stats = ckpt["normalizer"]
        result.update(normalizer_mean=stats["mean"].tolist(), normalizer_std=stats["var"].sqrt().tolist())
    print(f"{name}, policy of iteration {ckpt['iteration']} ({ckpt['samples'] / 1e6:.2f} M samples), deterministic, "
          f"{episodes} episodes each:")
    print(f"  Gymnasium's env (gymnasium.make, float64): return {gym_return:.1f} ± {gym['std']:.1f}, "
          f"length {gym['length']:.0f}   per seed: "
          + ", ".join(f"{s['seed']}: {s['return']:.1f}" for s in gym["per_seed"]))
    print(f"  warpgym's env (float32, {device}), the same starts: return {ours['eval/return']:.1f} "
          f"± {np.std(ours_r):.1f}, length {ours['eval/length']:.0f}")
    print("  reward terms, mean per episode (Gymnasium | warpgym): " + terms_line(
        {"gymnasium": gym["terms"], "warpgym": result["warpgym_terms"]},
        {"gymnasium": gym_return, "warpgym": ours["eval/return"]},
        {"gymnasium": gym["length"], "warpgym": ours["eval/length"]}))
    print(f"  held in Gymnasium's env (Gymnasium / warpgym; for costs warpgym / Gymnasium): {ratio:.3f}")
    if args.nudge:
        print(f"  Gymnasium's env, every start moved by {args.nudge:g}: "
              f"return {extra['gymnasium_nudged_return']:.1f}; "
              f"Gymnasium / itself so moved: {extra['gymnasium_over_gymnasium_nudged']:.3f}")
    if args.env_version == 4:
        print(f"  Gymnasium's v4 ({task.version_name(4)}), the same reset seeds: return {old['return']:.1f} "
              f"± {old['std']:.1f}, length {old['length']:.0f}; v4 / v5 (for costs v5 / v4): {extra['v4_over_v5']:.3f}")
        print("  reward terms, mean per episode (v5 | v4): " + terms_line(
            {"v5": gym["terms"], "v4": old["terms"]}, {"v5": gym_return, "v4": old["return"]},
            {"v5": gym["length"], "v4": old["length"]}))
    if args.json:
        write_json(args.json, result)
    print(f"Next: warpgym play {args.checkpoint} --gif {name.lower()}.gif draws it"
          + (f" (the numbers: {args.json})." if args.json else " (--json OUT writes the numbers)."))
    return 0


if __name__ == "__main__":
    sys.exit(main())
