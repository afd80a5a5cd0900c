"""Frames of warpgym robots, drawn by MuJoCo's OpenGL renderer from the same MJCF, headless.

The physics stays in warpgym: each frame the robots' states (warpgym's layout, docs/tensor_api.md)
are written into native MuJoCo copies of the robot (``warpgym.native.robots``, the mapping
``warpgym sim2sim`` uses) and drawn; nothing is simulated here. ``K`` robots are drawn side by
side in one scene, as Isaac Gym's viewer shows its envs, each shifted by its place in a grid.

OpenGL comes from EGL (an NVIDIA driver's on a GPU machine, Mesa's software renderer on a CPU-only
one) or OSMesa, chosen here rather than by ``MUJOCO_GL`` at ``mujoco``'s import: by the time a
clip is asked for, the physics solver has long imported ``mujoco``. ``MUJOCO_GL=egl|osmesa``
still picks one; other values (GLFW needs a display) fall back to trying both.
"""

from __future__ import annotations

import atexit
import math
import os
from dataclasses import dataclass

import numpy as np

from warpgym.native.robots import NativeRobot
from warpgym.media.ground_colours import colour_ground
from warpgym.tasks.legged.model import compile_task_scene

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


@dataclass
class Camera:
    """A camera that follows the robots: it looks at their mean position at a fixed height (the
    torso's bobbing would shake the picture), from ``distance`` metres at the given angles (degrees;
    azimuth 90 looks along +y, so a robot running along +x crosses the frame left to right)."""

    distance: float = 4.0
    azimuth: float = 110.0
    elevation: float = -18.0
    height: float = 0.4


def grid_offsets(copies: int, spacing: float) -> np.ndarray:
    """(copies, 3) shifts that lay robots out on a near-square grid, rows across the running direction."""
    cols = math.ceil(math.sqrt(copies))
    k = np.arange(copies)
    out = np.zeros((copies, 3))
    out[:, 0] = -(k // cols) * spacing
    out[:, 1] = (k % cols - (cols - 1) / 2) * spacing
    return out


class RobotRenderer:
    """Draws ``copies`` robots of a task from warpgym-layout states.

    Args:
        task: "Ant", "Humanoid" or a ``LocomotionTask``.
        copies: robots per frame (a grid of them when more than one).
        width, height: frame size in pixels (even numbers, as video encoders want them).
        spacing: metres between neighbouring robots in the grid.
        camera: a ``Camera``; the default frames one robot, further away for a grid.
    """

    def __init__(self, task="Ant", copies: int = 1, width: int = 640, height: int = 480,
                 spacing: float | None = None, camera: Camera | None = None):
        if not isinstance(copies, int) or copies < 1:
            raise ValueError(f"copies={copies!r} must be a positive integer")
        self.check_size(width, height)
        import mujoco  # noqa: PLC0415

        self._mj = mujoco
        self.robot = NativeRobot(task, copies=copies, visual=True)
        self.task = self.robot.task
        self.copies, self.width, self.height = copies, width, height
        tall = self.task.robot.lower().startswith("humanoid")
        self.spacing = spacing if spacing is not None else (2.0 if tall else 2.5)
        self.offsets = grid_offsets(copies, self.spacing)
        cols = math.ceil(math.sqrt(copies))
        self.camera = camera or Camera(distance=(4.5 if tall else 3.5) + 1.2 * self.spacing * (cols - 1),
                                       height=0.9 if tall else 0.4)
        model = self.robot.model
        self._context = gl_context(width, height)
        self._scene = mujoco.MjvScene(model, maxgeom=max(1000, 2 * copies * model.ngeom + 100))
        self._option = mujoco.MjvOption()
        self._perturb = mujoco.MjvPerturb()
        self._cam = mujoco.MjvCamera()
        self._cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        self._gpu = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._gpu)
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._warm = False

    @staticmethod
    def check_size(width: int, height: int) -> None:
        ok = all(isinstance(v, int) and v >= 2 and v % 2 == 0 for v in (width, height))
        if not ok or width > 1920 or height > 1080:
            raise ValueError(f"frame size {width!r}x{height!r} must be even and at most 1920x1080 (video "
                             "encoders want even sizes); pick e.g. --width 640 --height 480")

    def render(self, root_pose, root_vel, dof_pos, dof_vel) -> np.ndarray:
        """One (height, width, 3) uint8 frame of the robots in these states (one row per copy)."""
        mj, robot = self._mj, self.robot
        robot.set_state(root_pose, root_vel, dof_pos, dof_vel)
        self._context.make_current()
        center = (np.asarray(root_pose, np.float64)[:, :3] + self.offsets).mean(axis=0)
        cam = self._cam
        cam.lookat[:] = (center[0], center[1], self.camera.height)
        cam.distance, cam.azimuth, cam.elevation = self.camera.distance, self.camera.azimuth, self.camera.elevation
        for _ in range(1 if self._warm else 2):  # the first scene of a context draws a few levels off: twice
            self._draw(cam)
        self._warm = True
        pixels = np.empty((self.height, self.width, 3), np.uint8)
        mj.mjr_readPixels(pixels, None, self._rect, self._gpu)
        return np.flipud(pixels).copy()  # OpenGL's rows run bottom to top

    def _draw(self, cam) -> None:
        mj, robot, scene = self._mj, self.robot, self._scene
        # static geoms (the floor) once, then each robot's geoms shifted to its place in the grid
        mj.mjv_updateScene(robot.model, robot.data[0], self._option, self._perturb, cam,
                           mj.mjtCatBit.mjCAT_STATIC, scene)
        for data, offset in zip(robot.data, self.offsets):
            first = scene.ngeom
            mj.mjv_addGeoms(robot.model, data, self._option, self._perturb, mj.mjtCatBit.mjCAT_DYNAMIC, scene)
            if offset.any():
                for i in range(first, scene.ngeom):
                    scene.geoms[i].pos[:] += offset
        mj.mjr_render(self._rect, scene, self._gpu)

    def close(self) -> None:
        """Free the OpenGL context now (left to the garbage collector at exit, EGL complains)."""
        if getattr(self, "_gpu", None) is not None:
            self._gpu.free()
            self._gpu = None
        if getattr(self, "_context", None) is not None:
            self._context.free()
            self._context = None

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


RENDER_MODES = ("rgb_array", "human")


class EnvView:
    """What Gymnasium's ``render()`` shows of a warpgym env.

    ``"rgb_array"``: one (height, width, 3) frame per robot for the env's first ``robots`` robots,
    each with its own tracking camera (Gymnasium's vector convention: a tuple with a frame per env;
    ``gymnasium.wrappers.vector.RecordVideo`` tiles them). ``"human"``: MuJoCo's viewer window on the
    first robot, which needs a display; without one the constructor says so in one line.
    """

    def __init__(self, task, mode: str, robots: int = 1, width: int = 640, height: int = 480):
        if mode not in RENDER_MODES:
            raise ValueError(f"render_mode={mode!r}: choose one of {list(RENDER_MODES)} or None")
        if isinstance(robots, bool) or not isinstance(robots, int) or robots < 1:
            raise ValueError(f"render_robots={robots!r} must be a positive integer (how many robots render() draws)")
        self.task, self.mode, self.robots = task, mode, robots
        # [renderer, viewer]: freed by close(), or at exit before mujoco's own exit hook ends EGL (a
        # context left to the garbage collector after that raises in its destructor). The hook holds
        # the list, not the view, so an env that is dropped is still collected.
        self._open: list = [None, None]
        self._at_exit = None
        if mode == "human":
            if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.name == "nt"):
                raise RuntimeError("render_mode='human' opens MuJoCo's viewer, which needs a display, and this "
                                   "machine has none (DISPLAY is not set): use render_mode='rgb_array' for frames")
            self._robot = NativeRobot(task, copies=1, visual=True)
        else:
            RobotRenderer.check_size(width, height)
            self._size = (width, height)

    def render(self, states: dict):
        """``states``: warpgym-layout arrays (root_pose, root_vel, dof_pos, dof_vel) of at least
        ``robots`` rows. Returns a tuple of frames (rgb_array) or None (human)."""
        keys = ("root_pose", "root_vel", "dof_pos", "dof_vel")
        if self.mode == "human":
            return self._show({k: np.asarray(states[k])[:1] for k in keys})
        if self._open[0] is None:
            self._open[0] = RobotRenderer(self.task, copies=1, width=self._size[0], height=self._size[1])
            self._free_at_exit()
        return tuple(self._open[0].render(*(np.asarray(states[k])[i : i + 1] for k in keys))
                     for i in range(self.robots))

    def _show(self, state: dict) -> None:
        import mujoco.viewer  # noqa: PLC0415

        self._robot.set_state(state["root_pose"], state["root_vel"], state["dof_pos"], state["dof_vel"])
        if self._open[1] is None:
            self._open[1] = mujoco.viewer.launch_passive(self._robot.model, self._robot.data[0])
            self._free_at_exit()
        self._open[1].sync()

    def _free_at_exit(self) -> None:
        # registered after the GL library's own hook (made at its import), so run before it
        if self._at_exit is None:
            held = self._open
            self._at_exit = lambda: EnvView._free(held)
            atexit.register(self._at_exit)

    def close(self) -> None:
        EnvView._free(self._open)
        if self._at_exit is not None:
            atexit.unregister(self._at_exit)
            self._at_exit = None

    @staticmethod
    def _free(open_: list) -> None:
        renderer, viewer = open_
        open_[:] = [None, None]
        if renderer is not None:
            renderer.close()
        if viewer is not None:
            viewer.close()


class SuiteView:
    """What Gymnasium's ``render()`` shows of one of its MuJoCo tasks simulated by warpgym: the same worlds
    drawn by Gymnasium's own env (its renderer, cameras and frame size), their states copied into it.

    ``"rgb_array"``: a tuple of (height, width, 3) frames, one per world for the first ``robots``;
    ``"human"``: Gymnasium's viewer window on the first world (needs a display).

    ``follow``: keep the root body in the middle of the frame. Gymnasium 1.4's free camera stays where
    the robot started, so a runner leaves its frames within seconds; clips of the locomotion tasks follow.
    (Gymnasium 1.2 draws from the model's tracking camera, where a file has one, and follows anyway.)"""

    def __init__(self, task, mode: str, robots: int = 1, width: int = 640, height: int = 480,
                 follow: bool = False):
        if mode not in RENDER_MODES:
            raise ValueError(f"render_mode={mode!r}: choose one of {list(RENDER_MODES)} or None")
        if isinstance(robots, bool) or not isinstance(robots, int) or robots < 1:
            raise ValueError(f"render_robots={robots!r} must be a positive integer (how many worlds render() draws)")
        if mode == "human" and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or os.name == "nt"):
            raise RuntimeError("render_mode='human' opens MuJoCo's viewer, which needs a display, and this machine "
                               "has none (DISPLAY is not set): use render_mode='rgb_array' for frames")
        if mode == "rgb_array":
            RobotRenderer.check_size(width, height)
            if os.environ.get("MUJOCO_GL", "").strip().lower() not in ("egl", "osmesa"):
                # Gymnasium's renderer reads MUJOCO_GL when it makes its context: point it at a headless one
                context = gl_context(16, 16)
                os.environ["MUJOCO_GL"] = "egl" if type(context).__module__.endswith("egl") else "osmesa"
                context.free()
        import gymnasium  # noqa: PLC0415

        args = {name: getattr(task, name) for name in task.argument_names()}
        self.robots, self.mode, self.follow = robots, mode, follow
        self._env = gymnasium.make(task.name, render_mode=mode, width=width, height=height, **args).unwrapped
        # closed at exit before mujoco's own exit hook ends EGL, as EnvView's renderer (the hook holds the env,
        # not the view)
        self._at_exit = self._env.close
        atexit.register(self._at_exit)

    def render(self, qpos: np.ndarray, qvel: np.ndarray):
        """``qpos``, ``qvel``: MuJoCo's layout, one row per world (at least ``robots`` rows)."""
        import mujoco  # noqa: PLC0415

        env = self._env
        frames = []
        for i in range(1 if self.mode == "human" else self.robots):
            env.data.qpos[:] = qpos[i]
            env.data.qvel[:] = qvel[i]
            mujoco.mj_forward(env.model, env.data)
            if self.follow:
                if env.mujoco_renderer.viewer is None:
                    env.render()  # Gymnasium makes its viewer, and sets its camera, on the first frame
                env.mujoco_renderer.viewer.cam.lookat[:2] = env.data.xpos[1, :2]  # body 1: the root
            frames.append(env.render())
        return None if self.mode == "human" else tuple(frames)

    def close(self) -> None:
        if self._env is not None:
            self._env.close()
            atexit.unregister(self._at_exit)
            self._env = None


class LeggedView:
    """Draws one world of a legged task from MuJoCo's qpos: the scene as MuJoCo compiles it (and its ground), its collision
    geometry shown (the file holds no visual meshes), the camera following the base from behind and above."""

    def __init__(self, task, width: int = 640, height: int = 480):
        import mujoco  # noqa: PLC0415

        RobotRenderer.check_size(width, height)
        self._mj = mujoco
        self.task, self.width, self.height = task, width, height
        compiled, ground = compile_task_scene(task)
        self.model = compiled.mjm  # with its generated ground, on rough tasks, each patch coloured by its kind
        if ground is not None:
            colour_ground(self.model, ground)
        self.data = mujoco.MjData(self.model)
        self.root = self.model.body(task.root_body).id
        tall = self.model.body_subtreemass[self.root] > 20.0  # a humanoid rather than a quadruped
        self._context = gl_context(width, height)
        self._scene = mujoco.MjvScene(self.model, maxgeom=1000)
        self._option = mujoco.MjvOption()
        self._option.geomgroup[3] = 1  # the collision geoms: what the robot is made of in this scene
        self._perturb = mujoco.MjvPerturb()
        self._cam = mujoco.MjvCamera()
        self._cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        self._cam.distance, self._cam.elevation = (3.0 if tall else 1.6), -15.0
        self._gpu = mujoco.MjrContext(self.model, mujoco.mjtFontScale.mjFONTSCALE_150)
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._gpu)
        self._rect = mujoco.MjrRect(0, 0, width, height)

    def render(self, qpos: np.ndarray) -> np.ndarray:
        mj = self._mj
        self.data.qpos[:] = qpos
        mj.mj_kinematics(self.model, self.data)
        self._context.make_current()
        cam = self._cam
        cam.lookat[:] = self.data.xpos[self.root]
        # behind the base, as its heading turns
        x = self.data.xmat[self.root].reshape(3, 3)[:, 0]
        cam.azimuth = math.degrees(math.atan2(x[1], x[0])) + 150.0
        for _ in range(2):  # the first scene of a context draws a few levels off: twice
            mj.mjv_updateScene(self.model, self.data, self._option, self._perturb, cam, mj.mjtCatBit.mjCAT_ALL,
                               self._scene)
            mj.mjr_render(self._rect, self._scene, self._gpu)
        pixels = np.empty((self.height, self.width, 3), np.uint8)
        mj.mjr_readPixels(pixels, None, self._rect, self._gpu)
        return np.flipud(pixels).copy()

    close = RobotRenderer.close
