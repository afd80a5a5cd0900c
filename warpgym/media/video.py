"""Video files of any family's frames: MP4 through PyAV (its wheels carry their own FFmpeg and x264, so no
system ffmpeg), GIF through Pillow. Both come with ``pip install "warpgym[video]"``.

``write_clip`` hands a clip's frames, drawn one control step at a time by a family's view
(``warpgym.media.robots``, ``.suite``, ``.legged``), to one writer a file, each at its own stride.
"""

from __future__ import annotations

import os

import numpy as np

INSTALL = 'pip install "warpgym[video]"'
CONTROL_FPS = 60  # one frame per 1/60 s control step


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


def write_clip(writers: list[VideoWriter], strides: dict[str, int], steps: int, draw) -> dict[str, int]:
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


def real_time_strides(dt: float, fps: int, gif: bool) -> tuple[int, int, int | None]:
    """For a clip whose control step lasts ``dt`` seconds (0.008 s for Gymnasium's Hopper, 0.05 s for its Ant):
    every how many steps a frame is kept, the file's frame rate and a GIF's frame time (ms), so that the clip
    plays in real time at about ``fps``."""
    stride = max(1, round(1.0 / (fps * dt)))
    if gif:  # GIFs count time in hundredths of a second
        frame_ms = max(10, round(stride * dt * 100) * 10)
        return stride, max(1, round(1000 / frame_ms)), frame_ms
    return stride, max(1, round(1.0 / (stride * dt))), None


def real_time_writers(outputs: dict[str, dict], dt: float) -> tuple[list[VideoWriter], dict[str, int]]:
    """A writer for each output (path -> ``{"fps": ..., "width": ...}``) of a clip of ``dt``-second steps, and the
    stride of each (``real_time_strides``), for ``write_clip``."""
    plans = {path: real_time_strides(dt, int(opt["fps"]), path.lower().endswith(".gif")) for path, opt in outputs.items()}
    writers = [VideoWriter(path, plans[path][1], opt.get("width"), plans[path][2]) for path, opt in outputs.items()]
    return writers, {path: plan[0] for path, plan in plans.items()}
