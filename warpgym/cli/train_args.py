"""The command line of `warpgym train`: its flags, and their checks with the errors that name the fix."""

from __future__ import annotations

import argparse
import math

from agents.config import PRESETS
from agents.data_parallel import MODES as MULTI_GPU_MODES

TASK_NAMES = {t.lower(): t for t in PRESETS}


def parse_args(argv=None, description: str | None = None):
    ap = argparse.ArgumentParser(description=description, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--task", default=None, help="Ant (default), Humanoid, or one of Gymnasium's MuJoCo tasks "
                                                 "(InvertedPendulum-v5 ... HumanoidStandup-v5)")
    ap.add_argument("--num-envs", type=int, default=None, help="default on a GPU: 8192 (Ant), 4096 (Humanoid); 64 on the CPU")
    ap.add_argument("--device", default=None, help="default: cuda:0 when present, else cpu")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-iterations", type=int, default=None)
    ap.add_argument("--total-steps", type=int, default=None, help="stop after this many samples")
    ap.add_argument("--time-limit", type=float, default=None, help="stop after this many seconds since start")
    ap.add_argument("--run-dir", default=None, help="default: runs/<Task>-<date>-<time>")
    ap.add_argument("--resume", default=None, metavar="RUN_DIR", help="continue the run saved in RUN_DIR")
    ap.add_argument("--eval-gap", type=float, default=None, help="seconds between deterministic evaluations")
    ap.add_argument("--eval-envs", type=int, default=None, help="envs per evaluation (the seed's eval env: 1)")
    ap.add_argument("--no-eval", action="store_true")
    ap.add_argument("--save-gap", type=int, default=None, help="iterations between checkpoints")
    ap.add_argument("--horizon-len", type=int, default=None)
    ap.add_argument("--batch-size", type=int, default=None)
    ap.add_argument("--repeat-times", type=int, default=None)
    ap.add_argument("--learning-rate", type=float, default=None)
    ap.add_argument("--episode-length", type=int, default=None, help="steps per episode (task default: 1000)")
    ap.add_argument("--substeps", type=int, default=None, help="physics substeps per 1/60 s step (default: the task's)")
    ap.add_argument("--physics", action="append", default=[], metavar="NAME=VALUE",
                    help="a physics setting (warpgym/sim/physics.py), e.g. --physics armature=0.05; repeat for more")
    ap.add_argument("--config", action="append", default=[], metavar="NAME=VALUE",
                    help="any PPO setting of agents/config.py's Config, e.g. --config gamma=0.999 --config "
                         "net_dims=256,256 --config reward_scale=0.1; repeat for more (a sweep's knobs)")
    ap.add_argument("--save-at", type=float, nargs="+", default=None, metavar="SECONDS",
                    help="also keep checkpoint-<iteration>.pt at the first iteration after each of these "
                         "wall-clock seconds since start, e.g. --save-at 60 120 (summary.json lists them)")
    ap.add_argument("--target", default=None, metavar="KEY=VALUE",
                    help="stop once a logged value reaches VALUE, e.g. --target eval/speed=9.5 (an evaluation's "
                         "forward speed) or --target eval/return=5850; summary.json records the row that did")
    ap.add_argument("--multi-gpu", default=None, choices=MULTI_GPU_MODES,
                    help="under torchrun, how the GPUs divide the work (agents/data_parallel.py): split (default: "
                         "--num-envs and --batch-size are the run's totals, the one-GPU algorithm in shorter "
                         "iterations), grow-batch (each GPU --num-envs envs, mini-batches G times larger) or "
                         "grow-steps (each GPU --num-envs envs, G times the mini-batch steps)")
    ap.add_argument("--keep-checkpoints", action="store_true",
                    help="keep checkpoint-<iteration>.pt at every save, not only the latest checkpoint.pt")
    ap.add_argument("--video", action="store_true",
                    help="record a clip of the evaluation episode into RUN_DIR/videos and TensorBoard "
                         "(drawn by a separate process; needs warpgym[video])")
    ap.add_argument("--video-every", type=int, default=1, metavar="N", help="record every N-th evaluation (default 1)")
    ap.add_argument("--video-length", type=int, default=300, metavar="STEPS",
                    help="control steps per clip (default 300: 5 s)")
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--no-cuda-graph", action="store_true",
                    help="run everything eagerly: no CUDA graph of the rollout or of the PPO update")
    ap.add_argument("--rollout-graph", choices=("step", "rollout", "off"), default="step",
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
    args = ap.parse_args(argv)
    check_values(ap, args)
    from warpgym.sim.physics import Physics, parse_setting  # noqa: PLC0415

    try:
        args.physics = dict(parse_setting(text) for text in args.physics)
        Physics.from_dict(args.physics)
    except ValueError as e:
        ap.error(f"--physics: {e}")
    try:
        args.config = parse_config(args.config)
    except ValueError as e:
        ap.error(f"--config: {e}")
    if args.video:
        if args.task is not None and args.task.endswith("-v5"):
            ap.error(f"--video: training clips draw warpgym's own robots only so far, not {args.task}; drop --video "
                     "(a suite env draws its worlds with render_mode='rgb_array')")
        check_video_args(ap, args)
    return args


# Config fields a --config flag may not set: the envs are the command's, the seed is --seed
NOT_CONFIGURABLE = ("agent", "env_class", "env_args", "eval_env_class", "eval_env_args", "seed")


def parse_config(texts: list[str]) -> dict:
    """``["gamma=0.999", "net_dims=256,256"]`` -> {"gamma": 0.999, "net_dims": (256, 256)}; each name a Config
    field (agents/config.py), checked with the preset when the run is configured."""
    from dataclasses import fields  # noqa: PLC0415

    from agents.config import Config  # noqa: PLC0415
    from warpgym.sim.physics import parse_setting  # noqa: PLC0415

    names = {f.name for f in fields(Config)} - set(NOT_CONFIGURABLE)
    out = {}
    for text in texts:
        name, value = parse_setting(text)
        if name not in names:
            raise ValueError(f"{name!r} is not a PPO setting; choose from {sorted(names)}")
        if name in ("net_dims", "save_at"):
            try:
                value = tuple(int(v) if name == "net_dims" else float(v) for v in str(value).split(","))
            except ValueError:
                raise ValueError(f"{text!r}: write comma-separated numbers, e.g. {name}=256,128") from None
        out[name] = value
    return out


# flag -> a value that works, quoted in the error; every flag is checked before anything is built
POSITIVE = {"num_envs": 4096, "max_iterations": 500, "total_steps": 100_000_000, "eval_envs": 64, "save_gap": 50,
            "horizon_len": 16, "batch_size": 32768, "repeat_times": 4, "episode_length": 1000, "substeps": 2,
            "time_limit": 300, "learning_rate": 3e-4}
NON_NEGATIVE = {"eval_gap": 30, "seed": 0}


def flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def check_values(ap, args) -> None:
    """Impossible numbers and unknown tasks fail here, naming the flag and a value that works."""
    for name, example in {**POSITIVE, **NON_NEGATIVE}.items():
        v = getattr(args, name)
        if v is None:
            continue
        low_ok = v > 0 if name in POSITIVE else v >= 0
        if not (low_ok and math.isfinite(v)):
            need = "a positive" if name in POSITIVE else "a non-negative"
            ap.error(f"{flag(name)} {v}: must be {need} number, e.g. {flag(name)} {example}")
    for v in args.save_at or ():
        if not (v >= 0 and math.isfinite(v)):
            ap.error(f"--save-at {v}: must be non-negative seconds since start, e.g. --save-at 60 120")
    if args.task is not None and args.task.lower() not in TASK_NAMES:
        ap.error(f"--task {args.task!r}: choose one of {list(TASK_NAMES.values())}")
    if args.target is not None:
        from agents.config import Config  # noqa: PLC0415

        try:
            Config(target=args.target).target_pair()
        except ValueError:
            ap.error(f"--target {args.target!r}: write KEY=VALUE with a logged key and a number, e.g. "
                     "--target eval/speed=9.5 or --target eval/return=5850")
    if args.resume is not None:
        given = [f for f in ("num_envs", "horizon_len", "episode_length", "substeps", "multi_gpu")
                 if getattr(args, f) is not None]
        if given or args.physics:
            names = ", ".join([flag(f) for f in given] + (["--physics"] if args.physics else []))
            ap.error(f"{names}: a resumed run keeps the envs it was started with; drop {names} "
                     "or start a new run with --run-dir")


def with_flag_names(message: str) -> str:
    """A config error as the user wrote it: ``batch_size=8`` becomes ``--batch-size 8``."""
    for name in sorted({*POSITIVE, *NON_NEGATIVE}, key=len, reverse=True):
        message = message.replace(f"{name}=", f"{flag(name)} ").replace(f"lower {name}", f"lower {flag(name)}")
    return message


def check_video_args(ap, args) -> None:
    """--video fails here, before any model is built, if it cannot work."""
    if args.no_eval:
        ap.error("--video records the evaluation episode: drop --no-eval")
    for flag, value in (("--video-every", args.video_every), ("--video-length", args.video_length)):
        if value < 1:
            ap.error(f"{flag} {value}: must be a positive integer")
    from warpgym.media.video import why_no_video  # noqa: PLC0415

    reason = why_no_video(mp4=True, gif=True)  # an MP4 per clip, a GIF of it in TensorBoard
    if reason:
        ap.error(f"--video: {reason}")
