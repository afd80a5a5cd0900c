"""Score a trained policy where its task is judged (each family's ``evaluate`` in the module named for it, its
registry entry's ``evaluate``): Gymnasium's own env for Gymnasium's MuJoCo tasks, where
papers report; native MuJoCo for warpgym's Ant and Humanoid (``warpgym sim2sim``'s replay, which this runs) and
for the legged tasks (warpgym.native.legged: a fixed schedule of commands, tracking errors and falls beside the
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


def refuse_gymnasium_flags(args, what: str) -> None:
    """The flags only Gymnasium's env has, refused by name for a policy scored elsewhere (``what``)."""
    gym_only = [flag for flag, given in (("--nudge", args.nudge), ("--normalizer-from", args.normalizer_from),
                                         ("--env-version 4", args.env_version == 4)) if given]
    if gym_only:
        parser().error(f"{', '.join(gym_only)}: Gymnasium's env only; {args.checkpoint} holds a policy of {what}, "
                       "scored in native MuJoCo: drop it")


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

