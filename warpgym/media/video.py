"""Videos of warpgym robots: MP4 through PyAV (its wheels carry their own FFmpeg and x264, so no
system ffmpeg), GIF through Pillow. Both come with ``pip install "warpgym[video]"``.

``render_clip`` turns a stored sequence of states (warpgym's layout) into either file; the frames
come from ``warpgym.media.render``.
"""

from __future__ import annotations

import os

import numpy as np

INSTALL = 'pip install "warpgym[video]"'
CONTROL_FPS = 60  # one frame per 1/60 s control step
STATE_KEYS = ("root_pose", "root_vel", "dof_pos", "dof_vel")


def _import(module: str, what: str):
    try:
        return __import__(module)
    except ImportError as e:
        raise ImportError(f"{what} needs the '{module}' package, which is not installed: {INSTALL}") from e


def why_no_video(mp4: bool = True, gif: bool = True) -> str | None:
    """What stops clips from being written here, in a line that says how to fix it; None if nothing does.
    Checked before a run starts, so a missing package never costs a finished evaluation."""
    try:
        if mp4:
            import av  # noqa: F401,PLC0415
        if gif:
            import PIL  # noqa: F401,PLC0415
    except ImportError as e:
        return f"clips need the video extra ({e.name} is missing): {INSTALL}"
    from warpgym.media.render import RendererUnavailable, probe_renderer  # noqa: PLC0415

    try:
        probe_renderer()
    except RendererUnavailable as e:
        return str(e)
    return None


def frame_stride(fps: int, source_fps: int = CONTROL_FPS) -> int:
    """Keep every n-th control step: ``fps`` must divide the control rate."""
    if not isinstance(fps, int) or fps < 1 or source_fps % fps:
        ok = [f for f in range(1, source_fps + 1) if source_fps % f == 0]
        raise ValueError(f"fps={fps!r}: a clip keeps every n-th control step of {source_fps} Hz, so fps must "
                         f"divide {source_fps} (one of {ok})")
    return source_fps // fps


class VideoWriter:
    """Frames to ``path`` (.mp4 or .gif, by its suffix), written whole or not at all: the file appears
    under its name only once ``close`` has finished it.

    Args:
        path: where the clip goes.
        fps: frames per second of the file. GIF stores frame times in hundredths of a second, so
            its rates are those that divide 100 (20 fps: 50 ms a frame).
        width: resize frames to this width (height in proportion); default: as rendered.
        frame_ms: a GIF's frame time instead of 1000 / fps (a multiple of 10 ms): for a control rate
            that no GIF rate divides.
    """

    def __init__(self, path: str, fps: int, width: int | None = None, frame_ms: int | None = None):
        self.path, self.fps, self.width = path, int(fps), width
        self.frame_ms = frame_ms
        self.kind = os.path.splitext(path)[1].lower()
        if self.kind not in (".mp4", ".gif"):
            raise ValueError(f"video path {path!r} must end in .mp4 or .gif")
        if frame_ms is not None and (self.kind != ".gif" or frame_ms < 10 or frame_ms % 10):
            raise ValueError(f"frame_ms={frame_ms!r}: a GIF's frame time, a multiple of 10 ms (GIFs only)")
        if self.fps < 1 or (self.kind == ".gif" and frame_ms is None and 100 % self.fps):
            raise ValueError(f"fps={fps!r} for {path}: a GIF's rate must divide 100 (10, 20, 25 or 50)")
        if width is not None and (width < 2 or width % 2):
            raise ValueError(f"width={width!r} must be an even number of pixels")
        self._image = _import("PIL.Image", "writing videos").Image if self.kind == ".gif" or width else None
        if self.kind == ".mp4":
            self._av = _import("av", "writing MP4 video")
        self._tmp = f"{path}.tmp{os.getpid()}{self.kind}"
        self._container = self._stream = None
        self._gif: list = []
        self._palette = None
        self.frames = 0

    def write(self, frame: np.ndarray) -> None:
        """Append one (height, width, 3) uint8 RGB frame."""
        frame = np.ascontiguousarray(frame, dtype=np.uint8)
        if frame.ndim != 3 or frame.shape[2] != 3:
            raise ValueError(f"a frame must be (height, width, 3) RGB, got shape {frame.shape}")
        if self.width and frame.shape[1] != self.width:
            h = max(2, round(frame.shape[0] * self.width / frame.shape[1] / 2) * 2)
            frame = np.asarray(self._image.fromarray(frame).resize((self.width, h), self._image.LANCZOS))
        if self.kind == ".mp4":
            self._write_mp4(frame)
        else:
            self._write_gif(frame)
        self.frames += 1

    def _write_mp4(self, frame: np.ndarray) -> None:
        av = self._av
        if self._container is None:
            os.makedirs(os.path.dirname(os.path.abspath(self.path)), exist_ok=True)
            self._container = av.open(self._tmp, mode="w", format="mp4")
            self._stream = self._container.add_stream("libx264", rate=self.fps)
            self._stream.height, self._stream.width = frame.shape[:2]
            self._stream.pix_fmt = "yuv420p"
            self._stream.options = {"crf": "20", "preset": "medium"}
        packets = self._stream.encode(av.VideoFrame.from_ndarray(frame, format="rgb24"))
        self._container.mux(packets)

    def _write_gif(self, frame: np.ndarray) -> None:
        image = self._image.fromarray(frame)
        # one palette for the whole clip, taken from its first frame: no flicker between frames
        if self._palette is None:
            self._palette = image.quantize(colors=64, method=self._image.Quantize.MEDIANCUT)
            self._gif.append(self._palette)
        else:
            self._gif.append(image.quantize(palette=self._palette, dither=self._image.Dither.NONE))

    def close(self) -> str:
        """Finish the file and move it into place; returns its path."""
        if self.frames == 0:
            raise ValueError(f"no frames were written to {self.path}")
        if self.kind == ".mp4":
            self._container.mux(self._stream.encode(None))
            self._container.close()
        else:
            os.makedirs(os.path.dirname(os.path.abspath(self.path)), exist_ok=True)
            first, *rest = self._gif
            first.save(self._tmp, format="GIF", save_all=True, append_images=rest,
                       duration=self.frame_ms or 1000 // self.fps, loop=0)
            self._gif = []
        os.replace(self._tmp, self.path)
        return self.path

    def abort(self) -> None:
        """Drop a half-written clip."""
        if self._container is not None:
            try:
                self._container.close()
            except Exception:  # noqa: BLE001  (the file is removed either way)
                pass
        if os.path.exists(self._tmp):
            os.remove(self._tmp)

    def __enter__(self):
        return self

    def __exit__(self, exc_type, *exc) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


def render_clip(task, states: dict, outputs: dict[str, dict], width: int = 640, height: int = 480,
                copies: int | None = None) -> dict[str, int]:
    """Draw a stored state sequence into one or more files.

    Args:
        task: the task the states belong to ("Ant", "Humanoid" or a ``LocomotionTask``).
        states: ``STATE_KEYS`` -> arrays (T, K, n), one row per control step and robot.
        outputs: path -> ``{"fps": ..., "width": ...}`` (``width`` optional), e.g.
            ``{"ant.mp4": {"fps": 60}, "ant.gif": {"fps": 20, "width": 320}}``.
        copies: draw the first ``copies`` robots (default: all K, as a grid).
    Returns: path -> frames written.
    """
    from warpgym.media.render import RobotRenderer  # noqa: PLC0415

    missing = [k for k in STATE_KEYS if k not in states]
    if missing:
        raise ValueError(f"states lack {missing}: a clip needs {list(STATE_KEYS)}, each (steps, robots, n)")
    steps, have = np.asarray(states["root_pose"]).shape[:2]
    copies = copies or have
    if not 1 <= copies <= have:
        raise ValueError(f"copies={copies!r}: the states hold {have} robots")
    strides = {path: frame_stride(int(opt["fps"])) for path, opt in outputs.items()}
    writers = [VideoWriter(path, int(opt["fps"]), opt.get("width")) for path, opt in outputs.items()]
    with RobotRenderer(task, copies=copies, width=width, height=height) as renderer:
        return _write_clip(writers, strides, steps,
                           lambda t: renderer.render(*(np.asarray(states[k][t, :copies]) for k in STATE_KEYS)))


def _write_clip(writers: list[VideoWriter], strides: dict[str, int], steps: int, draw) -> dict[str, int]:
    """Each writer gets ``draw(t)`` of every ``strides[path]``-th step; all files are finished, or none
    is left behind. Returns path -> frames written."""
    try:
        for t in range(steps):
            due = [w for w in writers if t % strides[w.path] == 0]
            if due:
                frame = draw(t)
                for w in due:
                    w.write(frame)
        for w in writers:
            w.close()
    except BaseException:
        for w in writers:
            w.abort()
        raise
    return {w.path: w.frames for w in writers}


def suite_strides(dt: float, fps: int, gif: bool) -> tuple[int, int, int | None]:
    """For a clip of one of Gymnasium's tasks, whose control step lasts ``dt`` seconds (0.008 s for Hopper,
    0.05 s for Ant): every how many steps a frame is kept, the file's frame rate and a GIF's frame time
    (ms), so that the clip plays in real time at about ``fps``."""
    stride = max(1, round(1.0 / (fps * dt)))
    if gif:  # GIFs count time in hundredths of a second
        frame_ms = max(10, round(stride * dt * 100) * 10)
        return stride, max(1, round(1000 / frame_ms)), frame_ms
    return stride, max(1, round(1.0 / (stride * dt))), None


def render_suite_clip(task, states: dict, outputs: dict[str, dict], dt: float, width: int = 640,
                      height: int = 480) -> dict[str, int]:
    """Draw the first world of a stored clip of one of Gymnasium's tasks (``dof_pos``, ``dof_vel``: MuJoCo's
    qpos and qvel, (steps, worlds, n)) with Gymnasium's own renderer of the task, into each output
    (path -> ``{"fps": ..., "width": ...}``), in real time, the camera following the root body where the task says so
    (``camera_follows``: the runners). Returns path -> frames written."""
    from warpgym.media.render import SuiteView  # noqa: PLC0415

    missing = [k for k in ("dof_pos", "dof_vel") if k not in states]
    if missing:
        raise ValueError(f"states lack {missing}: a clip of a suite task needs MuJoCo's qpos and qvel")
    plans = {path: suite_strides(dt, int(opt["fps"]), path.lower().endswith(".gif")) for path, opt in outputs.items()}
    writers = [VideoWriter(path, plans[path][1], opt.get("width"), plans[path][2]) for path, opt in outputs.items()]
    view = SuiteView(task, "rgb_array", 1, width, height, follow=task.camera_follows)
    try:
        return _write_clip(writers, {p: plan[0] for p, plan in plans.items()}, np.asarray(states["dof_pos"]).shape[0],
                           lambda t: view.render(np.asarray(states["dof_pos"][t], dtype=np.float64),
                                                 np.asarray(states["dof_vel"][t], dtype=np.float64))[0])
    finally:
        view.close()


def draw_robot_clip(env, states: dict, outputs: dict[str, dict], width: int, height: int) -> tuple[dict, dict]:
    """A clip of warpgym's robots (every recorded robot, a grid): (path -> frames written, what it measured)."""
    from warpgym.media.clips import clip_forward_speed  # noqa: PLC0415

    shown = states["root_pose"].shape[0] - 1  # steps after the first frame
    measured = {"clip/forward_speed": float(clip_forward_speed(env.task, states).mean())}
    print(f"clip: {shown} steps ({shown * env.task.dt:.1f} s) of {states['root_pose'].shape[1]} robot(s): forward "
          f"speed {measured['clip/forward_speed']:.2f} m/s")
    return render_clip(env.task, states, outputs, width, height), measured


def draw_suite_clip(env, states: dict, outputs: dict[str, dict], width: int, height: int) -> tuple[dict, dict]:
    """A clip of one of Gymnasium's tasks (its first world, Gymnasium's renderer): (path -> frames, {})."""
    shown = states["dof_pos"].shape[0] - 1
    print(f"clip: {shown} steps ({shown * env.sim.dt:.1f} s) of one world")
    return render_suite_clip(env.task, states, outputs, env.sim.dt, width, height), {}


def draw_legged_clip(env, states: dict, outputs: dict[str, dict], width: int, height: int) -> tuple[dict, dict]:
    """A clip of a legged task (its first world, MuJoCo's renderer of the scene), in real time: (path -> frames,
    {})."""
    from warpgym.media.render import LeggedView  # noqa: PLC0415

    qpos = np.asarray(states["dof_pos"])
    shown = qpos.shape[0] - 1
    print(f"clip: {shown} steps ({shown * env.sim.dt:.1f} s) of one world")
    plans = {path: suite_strides(env.sim.dt, int(opt["fps"]), path.lower().endswith(".gif")) for path, opt in outputs.items()}
    writers = [VideoWriter(path, plans[path][1], opt.get("width"), plans[path][2]) for path, opt in outputs.items()]
    view = LeggedView(env.task, width, height)
    try:
        return _write_clip(writers, {p: plan[0] for p, plan in plans.items()}, qpos.shape[0],
                           lambda t: view.render(np.asarray(qpos[t][0], dtype=np.float64))), {}
    finally:
        view.close()
