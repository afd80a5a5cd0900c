"""What every family's frames share: a headless OpenGL context for MuJoCo's renderer, an offscreen frame of a
MuJoCo model, the checks of a frame size and a render mode, and closing a renderer before MuJoCo's exit hook.

The physics stays in warpgym: a family's view (``warpgym.media.robots``, ``.suite``, ``.legged``) writes the
simulated states into native MuJoCo and draws them; nothing is simulated here.

OpenGL comes from EGL (an NVIDIA driver's on a GPU machine, Mesa's software renderer on a CPU-only
one) or OSMesa, chosen here rather than by ``MUJOCO_GL`` at ``mujoco``'s import: by the time a
clip is asked for, the physics solver has long imported ``mujoco``. ``MUJOCO_GL=egl|osmesa``
still picks one; other values (GLFW needs a display) fall back to trying both.
"""

from __future__ import annotations

import atexit
import os

import numpy as np

INSTALL_GL = ("install an OpenGL that needs no display: the NVIDIA driver's EGL on a GPU machine, Mesa's on "
              "a CPU-only one (Debian/Ubuntu: apt install libegl1 libgl1-mesa-dri) or OSMesa "
              "(apt install libosmesa6), then set MUJOCO_GL=egl or MUJOCO_GL=osmesa")


class RendererUnavailable(RuntimeError):
    """No headless OpenGL context could be made; the message says what was tried and what to install."""


def gl_context(width: int, height: int):
    """An offscreen OpenGL context, current on this thread: the backend ``MUJOCO_GL`` names, else
    EGL, then OSMesa."""
    asked = os.environ.get("MUJOCO_GL", "").strip().lower()
    # GLFW is left out: without a display it hands back a dead context instead of failing
    backends = [asked] if asked in ("egl", "osmesa") else ["egl", "osmesa"]
    tried = []
    for backend in backends:
        try:
            if backend == "egl":
                from mujoco.egl import GLContext  # noqa: PLC0415
            else:
                from mujoco.osmesa import GLContext  # noqa: PLC0415
            context = GLContext(width, height)
            context.make_current()
            return context
        except Exception as e:  # noqa: BLE001  (each backend fails its own way; all are reported)
            first_line = (str(e).strip().splitlines() or [""])[0][:160]
            tried.append(f"{backend}: {type(e).__name__}: {first_line}")
    raise RendererUnavailable(f"no headless OpenGL context for MuJoCo's renderer (tried {'; '.join(tried)}); "
                              f"{INSTALL_GL}")


def probe_renderer() -> None:
    """Raise ``RendererUnavailable`` now if no frame could be drawn later."""
    gl_context(16, 16).free()


RENDER_MODES = ("rgb_array", "human")


def check_size(width: int, height: int) -> None:
    ok = all(isinstance(v, int) and v >= 2 and v % 2 == 0 for v in (width, height))
    if not ok or width > 1920 or height > 1080:
        raise ValueError(f"frame size {width!r}x{height!r} must be even and at most 1920x1080 (video "
                         "encoders want even sizes); pick e.g. --width 640 --height 480")


def check_view(mode: str, robots: int, what: str = "robots") -> None:
    """A Gymnasium ``render_mode`` and the count of worlds ``render()`` draws, refused in one line each; "human"
    refused too on a machine without a display."""
    if mode not in RENDER_MODES:
        raise ValueError(f"render_mode={mode!r}: choose one of {list(RENDER_MODES)} or None")
    if isinstance(robots, bool) or not isinstance(robots, int) or robots < 1:
        raise ValueError(f"render_robots={robots!r} must be a positive integer (how many {what} render() draws)")
    if mode == "human" and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.name == "nt"):
        raise RuntimeError("render_mode='human' opens MuJoCo's viewer, which needs a display, and this machine "
                           "has none (DISPLAY is not set): use render_mode='rgb_array' for frames")


class Offscreen:
    """An offscreen frame of one MuJoCo model: the GL context, MuJoCo's render context and scene; ``read()`` after
    ``mujoco.mjr_render(offscreen.rect, scene, offscreen.gpu)`` returns the frame."""

    def __init__(self, model, width: int, height: int, maxgeom: int = 1000):
        import mujoco  # noqa: PLC0415

        check_size(width, height)
        self.width, self.height = width, height
        self._context = gl_context(width, height)
        self.scene = mujoco.MjvScene(model, maxgeom=maxgeom)
        self.option = mujoco.MjvOption()
        self.perturb = mujoco.MjvPerturb()
        self.camera = mujoco.MjvCamera()
        self.camera.type = mujoco.mjtCamera.mjCAMERA_FREE
        self.gpu = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self.gpu)
        self.rect = mujoco.MjrRect(0, 0, width, height)

    def make_current(self) -> None:
        self._context.make_current()

    def read(self) -> np.ndarray:
        """The frame drawn last, (height, width, 3) uint8, top row first."""
        import mujoco  # noqa: PLC0415

        pixels = np.empty((self.height, self.width, 3), np.uint8)
        mujoco.mjr_readPixels(pixels, None, self.rect, self.gpu)
        return np.flipud(pixels).copy()  # OpenGL's rows run bottom to top

    def close(self) -> None:
        """Free the OpenGL context now (left to the garbage collector at exit, EGL complains)."""
        if getattr(self, "gpu", None) is not None:
            self.gpu.free()
            self.gpu = None
        if getattr(self, "_context", None) is not None:
            self._context.free()
            self._context = None


class ClosedAtExit:
    """Closes what it holds at exit, before MuJoCo's own exit hook ends EGL (a context left to the garbage collector
    after that raises in its destructor). The hook holds the list of closers, not the view, so a view that is
    dropped is still collected."""

    def __init__(self):
        self.held: list = []
        self._hook = None

    def hold(self, thing) -> None:
        self.held.append(thing)
        if self._hook is None:  # registered after the GL library's own hook (made at its import), so run before it
            held = self.held
            self._hook = lambda: ClosedAtExit._close(held)
            atexit.register(self._hook)

    def close(self) -> None:
        ClosedAtExit._close(self.held)
        if self._hook is not None:
            atexit.unregister(self._hook)
            self._hook = None

    @staticmethod
    def _close(held: list) -> None:
        things, held[:] = list(held), []
        for thing in things:
            thing.close()
