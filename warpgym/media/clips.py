"""Clips of evaluation episodes: states recorded on the device, drawn and encoded elsewhere.

``StateRecorder`` copies the first robots' states into device buffers after every evaluation step
(a few small copies, no host synchronisation); ``EvalVideoRecorder`` hands each finished episode to
a separate process that draws it, writes ``videos/eval-<iteration>.mp4`` and puts a GIF of it into
TensorBoard, so training never waits for a frame. Both follow the recorder protocol of
``agents/protocol.py``.

    python -m warpgym.media.clips CLIP.npz --mp4 OUT.mp4 [--gif OUT.gif] [--tensorboard DIR --step N]

draws a stored clip (what the background process runs).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

import numpy as np
import torch

from warpgym.media.robots import STATE_KEYS, render_clip
from warpgym.media.video import frame_stride


class StateRecorder:
    """The states of ``copies`` envs from env ``first`` on at each of ``steps`` control steps (the reset state
    first), kept on the env's device until ``states()`` reads them."""

    def __init__(self, steps: int, copies: int = 1, keys: tuple[str, ...] = STATE_KEYS, first: int = 0):
        if not isinstance(steps, int) or steps < 1 or not isinstance(copies, int) or copies < 1:
            raise ValueError(f"steps={steps!r} and copies={copies!r} must be positive integers")
        if not isinstance(first, int) or first < 0:
            raise ValueError(f"first={first!r} must be an env index >= 0")
        self.steps, self.copies, self.keys, self.first = steps, copies, tuple(keys), first
        self._buffers: dict[str, torch.Tensor] | None = None
        self.count = 0
        self.task = None

    def capture(self, env) -> None:
        if self.count >= self.steps:
            return
        if self._buffers is None:
            if self.first + self.copies > env.num_envs:
                raise ValueError(f"envs {self.first} to {self.first + self.copies - 1} recorded, but the env has "
                                 f"{env.num_envs} robots")
            self.task = env.task
            # views of the sim's persistent state, made once (each Tensor API property builds a new view),
            # and each robot's step count in its episode, which tells a reset apart from a stride
            shown = slice(self.first, self.first + self.copies)
            self._sources = {k: getattr(env.sim, k)[shown] for k in self.keys}
            self._sources["episode_steps"] = env.episode_steps[shown]
            self._buffers = {k: torch.empty((self.steps, *v.shape), dtype=v.dtype, device=env.device)
                             for k, v in self._sources.items()}
        for key, buf in self._buffers.items():
            buf[self.count].copy_(self._sources[key])
        self.count += 1

    def states(self) -> dict[str, np.ndarray]:
        """What was captured, on the host (one transfer per state array)."""
        if self._buffers is None or self.count == 0:
            raise ValueError("nothing was captured: pass the recorder to agents.evaluate.evaluate first")
        return {k: b[: self.count].cpu().numpy() for k, b in self._buffers.items()}

    def clear(self) -> None:
        self.count = 0


class EvalVideoRecorder(StateRecorder):
    """Records one clip every ``every`` evaluations during training (``warpgym train --video``).

    Args:
        run_dir: clips go to ``run_dir/videos``, their GIFs into ``run_dir/tensorboard``.
        steps: control steps per clip (300: 5 s).
        every: record every n-th evaluation.
        fps: frames per second of the MP4 (the GIF in TensorBoard runs at 20).
        width, height: frame size.
        copies: robots per clip, drawn side by side.
    """

    def __init__(self, run_dir: str, steps: int = 300, every: int = 1, fps: int = 30, width: int = 480,
                 height: int = 360, copies: int = 1, print_fn=print):
        super().__init__(steps, copies)
        frame_stride(fps)
        if not isinstance(every, int) or every < 1:
            raise ValueError(f"every={every!r} must be a positive integer (record every n-th evaluation)")
        self.dir = os.path.join(run_dir, "videos")
        self.tensorboard = os.path.join(run_dir, "tensorboard")
        self.every, self.fps, self.width, self.height = every, fps, width, height
        self.print = print_fn
        self._evaluations = 0
        self._queue: list[list[str]] = []
        self._running: tuple[subprocess.Popen, str] | None = None
        self.written: list[str] = []

    def capture(self, env) -> None:
        if self._evaluations % self.every == 0:
            super().capture(env)

    def finish(self, iteration: int, samples: int) -> None:
        """The evaluation is over: queue its clip for drawing (nothing here waits for it)."""
        recorded = self._evaluations % self.every == 0 and self.count > 0
        self._evaluations += 1
        if not recorded:
            return
        os.makedirs(self.dir, exist_ok=True)
        stem = os.path.join(self.dir, f"eval-{iteration:06d}")
        meta = {"task": self.task.name, "iteration": iteration, "samples": samples, "width": self.width,
                "height": self.height, "fps": self.fps}
        np.savez(f"{stem}.npz", meta=json.dumps(meta), **self.states())
        self.clear()
        self._queue.append([sys.executable, "-m", "warpgym.media.clips", f"{stem}.npz", "--mp4", f"{stem}.mp4",
                            "--tensorboard", self.tensorboard, "--step", str(samples), "--remove-input"])
        self._poll()

    def _poll(self, wait: bool = False) -> None:
        while True:
            if self._running is not None:
                proc, out = self._running
                if proc.poll() is None and not wait:
                    return
                if proc.wait() == 0:
                    self.written.append(out)
                else:
                    self.print(f"warning: drawing {out} failed (exit {proc.returncode}); see {self.dir}/render.log. "
                               "Training goes on without the clip")
                self._running = None
            if not self._queue:
                return
            cmd = self._queue.pop(0)
            package_root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
            # Drawing yields to training: a lower CPU priority, and Mesa's software renderer (a
            # CPU-only machine) on one thread instead of all of them.
            env = {**os.environ, "PYTHONPATH": os.pathsep.join([package_root, os.environ.get("PYTHONPATH", "")]),
                   "LP_NUM_THREADS": os.environ.get("LP_NUM_THREADS", "1")}
            with open(os.path.join(self.dir, "render.log"), "a") as log:
                proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env,
                                        preexec_fn=lambda: os.nice(10) if hasattr(os, "nice") else None)
            self._running = (proc, cmd[cmd.index("--mp4") + 1])

    def close(self) -> None:
        """Wait for the clips still being drawn."""
        if self._running is not None or self._queue:
            self.print(f"waiting for {len(self._queue) + (self._running is not None)} clip(s) to be drawn")
        self._poll(wait=True)


def tensorboard_gif(logdir: str, tag: str, gif: bytes, width: int, height: int, step: int) -> None:
    """An animated GIF as a TensorBoard image summary (TensorBoard plays it), in its own event file
    beside the metrics, so the training process's writer is never touched."""
    from tensorboard.compat.proto import event_pb2, summary_pb2  # noqa: PLC0415
    from tensorboard.summary.writer.event_file_writer import EventFileWriter  # noqa: PLC0415

    image = summary_pb2.Summary.Image(height=height, width=width, colorspace=3, encoded_image_string=gif)
    summary = summary_pb2.Summary(value=[summary_pb2.Summary.Value(tag=tag, image=image)])
    writer = EventFileWriter(logdir, filename_suffix=".video")
    writer.add_event(event_pb2.Event(summary=summary, step=step))
    writer.close()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Draw a stored clip (written by EvalVideoRecorder).")
    ap.add_argument("clip", help=".npz of states and their meta")
    ap.add_argument("--mp4", required=True)
    ap.add_argument("--tensorboard", default=None, help="also put a 20 fps GIF of it into this TensorBoard dir")
    ap.add_argument("--step", type=int, default=0)
    ap.add_argument("--remove-input", action="store_true")
    args = ap.parse_args(argv)
    with np.load(args.clip, allow_pickle=False) as z:  # plain arrays and a JSON string: no code
        meta = json.loads(str(z["meta"]))
        states = {k: z[k] for k in STATE_KEYS}
    outputs = {args.mp4: {"fps": meta["fps"]}}
    gif = None
    if args.tensorboard:
        gif = os.path.splitext(args.mp4)[0] + ".gif"
        outputs[gif] = {"fps": 20, "width": min(320, meta["width"])}
    frames = render_clip(meta["task"], states, outputs, meta["width"], meta["height"])
    if gif:
        with open(gif, "rb") as f:
            data = f.read()
        from PIL import Image  # noqa: PLC0415

        with Image.open(gif) as im:
            w, h = im.size
        tensorboard_gif(args.tensorboard, "eval/video", data, w, h, args.step)
        os.remove(gif)
    if args.remove_input:
        os.remove(args.clip)
    print(json.dumps({"clip": args.mp4, "frames": frames, "iteration": meta["iteration"]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
