"""The command line of `warpgym train`: its flags, and their checks with the errors that name the fix."""

from __future__ import annotations

import os

from agents.algos import ALGOS
from agents.data_parallel import MODES as MULTI_GPU_MODES
from warpgym.cli.flags import CommandParser, check_device, non_negative_float, non_negative_int, positive_float, \
    positive_int
from warpgym.tasks.registry import canonical, task_entry, task_names

TASK_NAMES = {t.lower(): t for t in task_names()}


def parser(description: str | None = None) -> CommandParser:
    """`warpgym train`'s flags, each number with its range and a value that works (warpgym.cli.flags)."""
    ap = CommandParser(prog="warpgym train", description=description)
    ap.add_argument("--task", default=None, help="Ant (default), Humanoid, one of Gymnasium's MuJoCo tasks "
                                                 "(InvertedPendulum-v5 ... HumanoidStandup-v5) or a legged task "
                                                 "(Go1VelocityFlat-v0, G1VelocityFlat-v0, Go1VelocityRough-v0, G1VelocityRough-v0, or with "
                                                 "--robot VelocityFlat-v0, VelocityRough-v0)")
    ap.add_argument("--robot", default=None, metavar="NAME|FILE.toml",
                    help="the robot of a legged velocity task: a zoo robot (a1, aliengo, go1, g1, ...) or a robot's "
                         "TOML definition naming its URDF or MJCF file (docs/robots.md); --task then defaults to "
                         "VelocityFlat-v0 (VelocityRough-v0 for rough ground)")
    ap.add_argument("--algo", default=None, choices=sorted(ALGOS),
                    help="the learner: ppo (default; several GPUs through torchrun) or sac (off-policy: soft "
                         "actor-critic with a distributional critic, a device replay and several updates per env "
                         "step, one GPU; agents/sac); its settings through --config, e.g. --config batch_size=4096")
    ap.add_argument("--num-envs", type=positive_int(4096), default=None,
                    help="default: the task's preset on a GPU (8192 for the Ant, 4096 for the Humanoid and "
                         "the legged tasks), fewer on the CPU")
    ap.add_argument("--device", default=None, help="default: cuda:0 when present, else cpu")
    ap.add_argument("--seed", type=non_negative_int(0), default=0)
    ap.add_argument("--max-iterations", type=positive_int(500), default=None)
    ap.add_argument("--total-steps", type=positive_int(100_000_000), default=None, help="stop after this many samples")
    ap.add_argument("--time-limit", type=positive_float(300), default=None,
                    help="stop after this many seconds since start")
    ap.add_argument("--run-dir", default=None, help="default: runs/<Task>-<date>-<time>")
    ap.add_argument("--resume", default=None, metavar="RUN_DIR", help="continue the run saved in RUN_DIR")
    ap.add_argument("--eval-gap", type=non_negative_float(30), default=None,
                    help="seconds between deterministic evaluations")
    ap.add_argument("--eval-envs", type=positive_int(64), default=None,
                    help="envs per evaluation (the ElegantRL tutorial's eval env: 1)")
    ap.add_argument("--no-eval", action="store_true")
    ap.add_argument("--save-gap", type=positive_int(50), default=None, help="iterations between checkpoints")
    ap.add_argument("--horizon-len", type=positive_int(16), default=None,
                    help="env steps per env per iteration (Config.horizon_len; default: the task's preset); under "
                         "--multi-gpu split-horizon the run's total, each of G GPUs stepping --horizon-len / G")
    ap.add_argument("--minibatch-size", "--batch-size", dest="minibatch_size", type=positive_int(32768), default=None,
                    help="samples per mini-batch step (Config.minibatch_size; --batch-size: its earlier name)")
    ap.add_argument("--repeat-times", type=positive_int(4), default=None)
    ap.add_argument("--learning-rate", type=positive_float(3e-4), default=None)
    ap.add_argument("--episode-length", type=positive_int(1000), default=None,
                    help="steps per episode (task default: 1000)")
    ap.add_argument("--substeps", type=positive_int(2), default=None,
                    help="physics substeps per 1/60 s step (default: the task's)")
    ap.add_argument("--physics", action="append", default=[], metavar="NAME=VALUE",
                    help="a physics setting (warpgym/sim/physics.py), e.g. --physics armature=0.05; repeat for more")
    ap.add_argument("--config", action="append", default=[], metavar="NAME=VALUE",
                    help="any setting of the learner's config (PPO: agents/config.py's Config; --algo sac: "
                         "agents/sac/config.py's SACConfig), e.g. --config gamma=0.999 --config net_dims=256,256 "
                         "--config reward_scale=0.1; repeat for more (a sweep's knobs)")
    ap.add_argument("--save-at", type=non_negative_float(60), nargs="+", default=None, metavar="SECONDS",
                    help="also keep checkpoint-<iteration>.pt at the first iteration after each of these "
                         "wall-clock seconds since start, e.g. --save-at 60 120 (summary.json lists them)")
    ap.add_argument("--target", default=None, metavar="KEY=VALUE",
                    help="stop once a logged value reaches VALUE, e.g. --target eval/speed=9.5 (an evaluation's "
                         "forward speed) or --target eval/return=5850; summary.json records the row that did")
    ap.add_argument("--multi-gpu", default=None, choices=MULTI_GPU_MODES,
                    help="under torchrun, how the GPUs divide the work (agents/data_parallel.py; the default is the "
                         "task's preset: split-horizon for Gymnasium's tasks, grow-kl for the others): grow-kl ("
                         "each GPU --num-envs envs, a mini-batch of --minibatch-size samples across them, G times the "
                         "mini-batch steps under a KL target G times desired_kl), grow-steps (the same under "
                         "desired_kl), split (--num-envs and --minibatch-size are the run's totals, the one-GPU "
                         "algorithm in shorter iterations), split-horizon (each GPU --num-envs envs for "
                         "--horizon-len / G steps: the one-GPU batch, collected in about 1/G of the time) or "
                         "grow-batch (each GPU --num-envs envs, mini-batches G times larger)")
    ap.add_argument("--keep-checkpoints", action="store_true",
                    help="keep checkpoint-<iteration>.pt at every save, not only the latest checkpoint.pt")
    ap.add_argument("--video", action="store_true",
                    help="record a clip of the evaluation episode into RUN_DIR/videos and TensorBoard "
                         "(drawn by a separate process; needs warpgym[video])")
    ap.add_argument("--video-every", type=positive_int(1), default=1, metavar="N",
                    help="record every N-th evaluation (default 1)")
    ap.add_argument("--video-length", type=positive_int(300), default=300, metavar="STEPS",
                    help="control steps per clip (default 300: 5 s)")
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--no-cuda-graph", action="store_true",
                    help="run everything eagerly: no CUDA graph of the rollout or of the PPO update")
    ap.add_argument("--rollout-graph", choices=("step", "rollout", "off"), default=None,
                    help="how rollouts are captured as CUDA graphs: one env step, replayed horizon_len times "
                         "(default: the fastest start), the whole rollout as one graph, or off (agents.collect)")
    ap.add_argument("--no-rollout-graph", action="store_const", const="off", dest="rollout_graph",
                    help="the same as --rollout-graph off")
    ap.add_argument("--no-mathdx", action="store_true",
                    help="compile Warp's tile Cholesky without libmathdx: a faster cold start (warpgym.compile.preload)")
    ap.add_argument("--overlap", action="store_true",
                    help="collect the next rollout while PPO learns from the last one (two CUDA streams; "
                         "each rollout learnt one update after the weights that drew it: agents.overlap)")
    ap.add_argument("--compile-update", action="store_true",
                    help="torch.compile the PPO loss (fused Triton kernels on CUDA; the first update compiles "
                         "for 3-16 s, the longer with an empty Inductor cache)")
    ap.add_argument("--profile", action="store_true",
                    help="time each phase of an iteration (synchronises the GPU between phases: slower)")
    return ap


def parse_args(argv=None, description: str | None = None):
    ap = parser(description)
    args = ap.parse_args(argv)
    check_values(ap, args)
    from warpgym.sim.physics import Physics, parse_setting  # noqa: PLC0415

    try:
        args.physics = dict(parse_setting(text) for text in args.physics)
        Physics.from_dict(args.physics)
    except ValueError as e:
        ap.error(f"--physics: {e}")
    try:
        # a resumed run's are checked against its own saved config
        algo = args.algo or "ppo"  # a resumed run's learner is its own (run_setup), its settings checked there
        args.config = (parse_config(args.config, saved_algo(args.resume)) if args.resume is not None
                       else task_config(args.task or "Ant", args.config, algo))
    except ValueError as e:
        ap.error(f"--config: {e}")
    if args.video:
        if not task_entry(args.task or "Ant").training_clips:
            ap.error(f"--video: training clips draw warpgym's own robots only so far, not {args.task}; drop --video "
                     "(a suite env draws its worlds with render_mode='rgb_array')")
        check_video_args(ap, args)
    return args


# Config fields a --config flag may not set: the envs are the command's, the seed is --seed
NOT_CONFIGURABLE = ("agent", "env_class", "env_args", "eval_env_class", "eval_env_args", "seed")


# the settings that are sequences of layer widths or of seconds, written comma-separated
WIDTHS = ("net_dims", "actor_dims", "critic_dims")


def saved_algo(run_dir: str) -> str:
    """The learner of a run directory's config.json (PPO's for a run saved before the off-policy learner)."""
    import json  # noqa: PLC0415

    from agents.algos import by_agent  # noqa: PLC0415

    try:
        with open(os.path.join(run_dir, "config.json")) as f:
            agent = json.load(f).get("agent")
    except (OSError, ValueError, AttributeError):
        return "ppo"  # the resume's own checks say what is wrong with the file
    try:
        return by_agent(agent).name
    except ValueError:
        return "ppo"


def parse_config(texts: list[str], algo: str = "ppo") -> dict:
    """``["gamma=0.999", "net_dims=256,256"]`` -> {"gamma": 0.999, "net_dims": (256, 256)}; each name a field of
    the learner's config (agents/config.py's Config, agents/sac/config.py's SACConfig), checked with the preset when
    the run is configured."""
    from dataclasses import fields  # noqa: PLC0415

    from agents.algos import algo as learner  # noqa: PLC0415
    from warpgym.sim.physics import parse_setting  # noqa: PLC0415

    config = learner(algo).config
    names = {f.name for f in fields(config)} - set(NOT_CONFIGURABLE)
    out = {}
    for text in texts:
        name, value = parse_setting(text)
        name = config.RENAMED.get(name, name)  # an earlier name still works
        if name not in names:
            raise ValueError(f"{name!r} is not a {algo.upper()} setting; choose from {sorted(names)}")
        if name in WIDTHS or name == "save_at":
            try:
                value = tuple(int(v) if name in WIDTHS else float(v) for v in str(value).split(","))
            except ValueError:
                raise ValueError(f"{text!r}: write comma-separated numbers, e.g. {name}=256,128") from None
        out[name] = value
    return out


def task_config(task: str, texts: list[str], algo: str = "ppo") -> dict:
    """``parse_config``'s settings, checked against ``task``'s preset: a ValueError names a wrong one."""
    from agents.algos import algo as learner  # noqa: PLC0415

    config = parse_config(texts, algo)
    learner(algo).config.from_preset(task_entry(task).preset_for(algo)).replace(**config)
    return config


def is_preset(task: str, texts: list[str]) -> bool:
    """Whether the settings ``texts`` leave ``task``'s preset as warpgym/tasks/presets.py holds it now (a candidate's
    settings once the preset took them)."""
    from agents.config import Config  # noqa: PLC0415

    preset = Config.from_preset(task_entry(task).preset)
    return preset.replace(**task_config(task, texts)) == preset


# Config fields that have a flag of their own: a config error names the flag (with_flag_names)
FLAG_FIELDS = ("num_envs", "max_iterations", "total_steps", "eval_envs", "save_gap", "horizon_len", "minibatch_size",
               "repeat_times", "episode_length", "substeps", "time_limit", "learning_rate", "eval_gap", "seed")


def flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def check_values(ap, args) -> None:
    """What the flags' types cannot check alone fails here, before anything is built, naming the flag and a
    value that works: the task, the device, the target, --config against the task's preset, a resume's flags."""
    if args.task is not None:
        try:
            args.task = canonical(args.task)
        except ValueError as e:  # an unknown name, or a user's module that does not import
            if ":" in args.task:
                ap.error(f"--task {args.task!r}: {e}")
            ap.error(f"--task {args.task!r}: choose one of {list(TASK_NAMES.values())}, or a task of your own "
                     "module: --task my_module:MyTask-v0")
    if args.robot is not None:
        check_robot(ap, args)
    if args.algo is not None and args.resume is not None:
        ap.error(f"--algo {args.algo}: a resumed run keeps the learner it was started with; drop --algo")
    if args.algo == "sac":
        ppo_only = [f for f, v in (("--horizon-len", args.horizon_len), ("--minibatch-size", args.minibatch_size),
                                   ("--repeat-times", args.repeat_times), ("--learning-rate", args.learning_rate),
                                   ("--multi-gpu", args.multi_gpu), ("--overlap", args.overlap or None),
                                   ("--compile-update", args.compile_update or None),
                                   ("--rollout-graph", args.rollout_graph)) if v is not None]
        if ppo_only:
            ap.error(f"{', '.join(ppo_only)}: PPO's settings; --algo sac takes its own through --config "
                     "(steps_per_iteration, batch_size, num_updates, actor_lr, critic_lr: agents/sac/config.py)")
        if int(os.environ.get("WORLD_SIZE", "1")) > 1:
            ap.error("--algo sac trains on one GPU: run python -m warpgym train --algo sac, not torchrun")
    if args.target is not None:
        from agents.config import Config  # noqa: PLC0415

        try:
            Config(target=args.target).target_pair()
        except ValueError:
            ap.error(f"--target {args.target!r}: write KEY=VALUE with a logged key and a number, e.g. "
                     "--target eval/speed=9.5 or --target eval/return=5850")
    check_device(ap, args.device)
    # rank 0 alone reads a resumed run's files (on several machines the others receive them): it alone checks
    if args.resume is not None and os.environ.get("RANK", "0") == "0" and \
            not os.path.isfile(os.path.join(args.resume, "config.json")):
        ap.error(f"--resume {args.resume}: no config.json there; pass a run directory written by warpgym train")
    if args.resume is not None:
        given = [f for f in ("num_envs", "horizon_len", "episode_length", "substeps", "multi_gpu")
                 if getattr(args, f) is not None]
        if given or args.physics:
            names = ", ".join([flag(f) for f in given] + (["--physics"] if args.physics else []))
            ap.error(f"{names}: a resumed run keeps the envs it was started with; drop {names} "
                     "or start a new run with --run-dir")


def check_robot(ap, args) -> None:
    """``--robot``: a new run's, of a legged task (VelocityFlat-v0 by default); its definition read, its scene built
    and its standing pose held in native MuJoCo before anything trains. A definition file is recorded by its
    absolute path, so that play, eval and export rebuild the same robot."""
    if args.resume is not None:
        ap.error(f"--robot {args.robot}: a resumed run keeps the robot it was started with; drop --robot")
    from warpgym.tasks.legged import get_legged_task  # noqa: PLC0415
    from warpgym.tasks.legged.robot_task import stands, zoo  # noqa: PLC0415

    args.task = args.task or "VelocityFlat-v0"
    try:
        get_legged_task(args.task)
    except ValueError:
        ap.error(f"--robot {args.robot}: --task {args.task} is not a legged velocity task; choose VelocityFlat-v0 or "
                 "VelocityRough-v0")

    if args.robot.lower() not in zoo():
        args.robot = os.path.abspath(os.path.expanduser(args.robot))
    try:
        stands(get_legged_task(args.task).replace(robot=args.robot))
    except ValueError as e:
        ap.error(f"--robot: {e}")


def with_flag_names(message: str) -> str:
    """A config error as the user wrote it: ``minibatch_size=8`` becomes ``--minibatch-size 8``."""
    for name in sorted(FLAG_FIELDS, key=len, reverse=True):
        message = message.replace(f"{name}=", f"{flag(name)} ").replace(f"lower {name}", f"lower {flag(name)}")
    return message


def check_video_args(ap, args) -> None:
    """--video fails here, before any model is built, if it cannot work."""
    if args.no_eval:
        ap.error("--video records the evaluation episode: drop --no-eval")
    from warpgym.media.video import why_no_video  # noqa: PLC0415

    reason = why_no_video(mp4=True, gif=True)  # an MP4 per clip, a GIF of it in TensorBoard
    if reason:
        ap.error(f"--video: {reason}")
