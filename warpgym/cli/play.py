"""Play a trained policy: mean return and forward speed of the deterministic policy, and videos.

    warpgym play runs/Ant-20261122-120000                      # its checkpoint.pt
    warpgym play runs/Ant-20261122-120000/checkpoint.pt --num-envs 256 --seed 3
    warpgym play runs/Ant-20261122-120000 --video ant.mp4     # one episode, tracking camera
    warpgym play runs/Ant-20261122-120000 --gif ant.gif --steps 300 --num-envs 9   # a 3x3 grid

Each env plays one episode with the action mean (no exploration noise), cut short after --steps.
Forward speed, here as everywhere in warpgym, is the distance travelled towards the target over the
time the episode lasted (warpgym.tasks.robots.LocomotionTask.forward_speed). With --video or --gif the
physics runs in warpgym as in training, and each control step's state is drawn by MuJoCo's renderer
from the same MJCF (headless: EGL or OSMesa; pip install "warpgym[video]"). MP4 runs at 60 fps (one
frame per 1/60 s control step), GIF at 20. A clip's forward speed counts the strides it shows; a
robot that fell and was reset inside it adds no travel for its reset.
"""

from __future__ import annotations

import os
import sys

from warpgym.cli import write_json
from warpgym.cli.flags import CommandParser, check_checkpoint, check_device, non_negative_int, positive_int


def parser() -> CommandParser:
    ap = CommandParser(prog="warpgym play", description=__doc__)
    ap.add_argument("checkpoint", help="a checkpoint file, or a run directory holding checkpoint.pt")
    ap.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                    help="a module of your own that registers the run's task (a run of --task MODULE:NAME); a run's "
                         "files never import code themselves")
    ap.add_argument("--num-envs", type=positive_int(64), default=None,
                    help="episodes at once (default 64 on a GPU, 4 on the CPU; 1 with --video/--gif, "
                         "more draws a grid of robots)")
    ap.add_argument("--device", default=None)
    ap.add_argument("--seed", type=non_negative_int(12345), default=12345)
    ap.add_argument("--video", default=None, metavar="OUT.mp4", help="write an MP4 of the episode")
    ap.add_argument("--gif", default=None, metavar="OUT.gif", help="write a GIF of the episode")
    ap.add_argument("--steps", type=positive_int(300), default=None,
                    help="control steps to play (default: one episode)")
    ap.add_argument("--width", type=positive_int(640), default=640, help="frame width in pixels (default 640)")
    ap.add_argument("--height", type=positive_int(480), default=480, help="frame height in pixels (default 480)")
    ap.add_argument("--fps", type=positive_int(60), default=60, help="MP4 frame rate, dividing 60 (default 60)")
    ap.add_argument("--gif-fps", type=positive_int(20), default=20,
                    help="GIF frame rate, dividing 60 and 100 (default 20)")
    ap.add_argument("--gif-width", type=positive_int(320), default=320, help="GIF width in pixels (default 320)")
    ap.add_argument("--json", default=None, metavar="OUT", help="also write the result as JSON")
    ap.add_argument("--world", type=non_negative_int(5), default=0,
                    help="the world a clip draws, of --num-envs (default the first); on rough ground the worlds share "
                         "the kinds of ground in blocks, in the order of the terrain's kinds")
    return ap


def parse_args(argv=None):
    ap = parser()
    args = ap.parse_args(argv)
    check_checkpoint(ap, args.checkpoint)
    check_device(ap, args.device)
    if args.video and not args.video.lower().endswith(".mp4"):
        ap.error(f"--video {args.video}: the file must end in .mp4 (use --gif for a GIF)")
    if args.gif and not args.gif.lower().endswith(".gif"):
        ap.error(f"--gif {args.gif}: the file must end in .gif")
    if args.world and not (args.video or args.gif):
        ap.error(f"--world {args.world}: the world a clip draws; add --gif OUT.gif or --video OUT.mp4")
    if args.world >= (args.num_envs or 1):
        ap.error(f"--world {args.world}: pass --num-envs {args.world + 1} or more (the clip's world among them)")
    if args.video or args.gif:
        from warpgym.media.video import frame_stride, why_no_video  # noqa: PLC0415

        reason = why_no_video(mp4=bool(args.video), gif=bool(args.gif))
        if reason:
            ap.error(f"--{'video' if args.video else 'gif'}: {reason}")
        try:
            frame_stride(args.fps)
            frame_stride(args.gif_fps)
            if 100 % args.gif_fps:
                raise ValueError(f"--gif-fps {args.gif_fps}: a GIF's rate must divide 100 and 60 (10 or 20)")
            from warpgym.media.render import check_size  # noqa: PLC0415

            check_size(args.width, args.height)
        except ValueError as e:
            ap.error(str(e))
    return args


def main(argv=None) -> int:
    args = parse_args(argv)
    import torch  # noqa: PLC0415

    from agents.checkpoint import load_for_command, policy_from_checkpoint  # noqa: PLC0415
    from agents.evaluate import evaluate  # noqa: PLC0415
    from warpgym.sim.device import resolve_device  # noqa: PLC0415
    from warpgym.envs import entry_point  # noqa: PLC0415
    from warpgym.cli import run_task  # noqa: PLC0415

    device = resolve_device(args.device)
    path, ckpt = load_for_command(args.checkpoint, torch.device(device))
    cfg = ckpt["config"]
    env_args = cfg["env_args"]
    task = env_args["task"]
    try:
        entry = run_task(task, args.imports)
    except ValueError as e:
        parser().error(f"{path}: {e}")
    filming = bool(args.video or args.gif)
    n = args.num_envs or (1 if filming else 64 if device.startswith("cuda") else 4)
    if args.world and entry.clip_all_worlds:
        parser().error(f"--world {args.world}: a clip of {task} draws all its worlds; drop it")
    if filming and n > 1 and not entry.clip_all_worlds:
        print(f"note: a clip of {task} draws world {args.world}; --num-envs {n} plays the others unseen")
    # the trained task as it was trained (episode length, substeps, physics), on this device
    env_class = entry_point(entry.vector_entry_point)
    env = env_class(**{**env_class.replay_args(env_args), "num_envs": n, "device": device, "seed": args.seed})
    policy, normalize = policy_from_checkpoint(ckpt, env.num_obs, env.num_actions, torch.device(device))
    steps = args.steps or env.task.episode_length
    recorder = None
    if filming:
        from warpgym.media.clips import StateRecorder  # noqa: PLC0415

        # the reset state, then one per step, of the worlds and the state the task's clips draw
        recorder = StateRecorder(steps + 1, copies=n if entry.clip_all_worlds else 1, first=args.world,
                                 **({"keys": entry.clip_keys} if entry.clip_keys else {}))
    result = evaluate(env, policy, normalize, steps, recorder)
    result = {"task": task, "checkpoint": path, "iteration": ckpt["iteration"], "samples": ckpt["samples"],
              "episodes": n, **result}
    # the tasks whose measure is a forward speed report it (a legged robot follows a command in any direction)
    speed = f", forward speed {result['eval/speed']:.2f} m/s" if entry.reports_speed else ""
    print(f"{task}, policy of iteration {ckpt['iteration']}, {n} episodes of the deterministic policy: "
          f"return {result['eval/return']:.1f}{speed}, length {result['eval/length']:.0f} steps (means)")
    if filming:
        outputs = {}
        if args.video:
            outputs[args.video] = {"fps": args.fps}
        if args.gif:
            outputs[args.gif] = {"fps": args.gif_fps, "width": min(args.gif_width, args.width)}
        frames, measured = entry.draw_clip(env, recorder.states(), outputs, args.width, args.height)
        result.update(measured)
        for out, count in frames.items():
            print(f"wrote {out}: {count} frames, {os.path.getsize(out) / 1e6:.2f} MB")
        result["videos"] = frames
    if args.json:
        write_json(args.json, result)
    nxt = [] if filming else [f"warpgym play {args.checkpoint} --gif {task.lower()}.gif draws it"]
    nxt.append(f"warpgym eval {args.checkpoint} scores it in {entry.scored_in}")
    print("Next: " + "; ".join(nxt) + (f" (the numbers: {args.json})." if args.json else
                                       " (--json OUT writes the numbers)."))
    return 0


if __name__ == "__main__":
    sys.exit(main())
