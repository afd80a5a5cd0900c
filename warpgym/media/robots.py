"""Frames and clips of warpgym's robots (Ant, Humanoid), drawn by MuJoCo's renderer from the same MJCF.

Each frame the robots' states (warpgym's layout, docs/tensor_api.md) are written into native MuJoCo copies of the
robot (``warpgym.native.robots``, the mapping ``warpgym sim2sim`` uses) and drawn. ``K`` robots are drawn side by
side in one scene, as Isaac Gym's viewer shows its envs, each shifted by its place in a grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from warpgym.media.render import ClosedAtExit, Offscreen, check_size, check_view
from warpgym.media.video import VideoWriter, frame_stride, write_clip
from warpgym.native.robots import NativeRobot

STATE_KEYS = ("root_pose", "root_vel", "dof_pos", "dof_vel")


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
        check_size(width, height)
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
        self._frame = Offscreen(model, width, height, maxgeom=max(1000, 2 * copies * model.ngeom + 100))
        self._warm = False

    def render(self, root_pose, root_vel, dof_pos, dof_vel) -> np.ndarray:
        """One (height, width, 3) uint8 frame of the robots in these states (one row per copy)."""
        self.robot.set_state(root_pose, root_vel, dof_pos, dof_vel)
        frame = self._frame
        frame.make_current()
        center = (np.asarray(root_pose, np.float64)[:, :3] + self.offsets).mean(axis=0)
        cam = frame.camera
        cam.lookat[:] = (center[0], center[1], self.camera.height)
        cam.distance, cam.azimuth, cam.elevation = self.camera.distance, self.camera.azimuth, self.camera.elevation
        for _ in range(1 if self._warm else 2):  # the first scene of a context draws a few levels off: twice
            self._draw()
        self._warm = True
        return frame.read()

    def _draw(self) -> None:
        mj, robot, f = self._mj, self.robot, self._frame
        # static geoms (the floor) once, then each robot's geoms shifted to its place in the grid
        mj.mjv_updateScene(robot.model, robot.data[0], f.option, f.perturb, f.camera, mj.mjtCatBit.mjCAT_STATIC,
                           f.scene)
        for data, offset in zip(robot.data, self.offsets):
            first = f.scene.ngeom
            mj.mjv_addGeoms(robot.model, data, f.option, f.perturb, mj.mjtCatBit.mjCAT_DYNAMIC, f.scene)
            if offset.any():
                for i in range(first, f.scene.ngeom):
                    f.scene.geoms[i].pos[:] += offset
        mj.mjr_render(f.rect, f.scene, f.gpu)

    def close(self) -> None:
        """Free the OpenGL context now (left to the garbage collector at exit, EGL complains)."""
        self._frame.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class EnvView:
    """What Gymnasium's ``render()`` shows of warpgym's robots.

    ``"rgb_array"``: one (height, width, 3) frame per robot for the env's first ``robots`` robots,
    each with its own tracking camera (Gymnasium's vector convention: a tuple with a frame per env;
    ``gymnasium.wrappers.vector.RecordVideo`` tiles them). ``"human"``: MuJoCo's viewer window on the
    first robot, which needs a display; without one the constructor says so in one line.
    """

    def __init__(self, task, mode: str, robots: int = 1, width: int = 640, height: int = 480):
        check_view(mode, robots)
        self.task, self.mode, self.robots = task, mode, robots
        self._renderer = self._viewer = None
        self._open = ClosedAtExit()
        if mode == "human":
            self._robot = NativeRobot(task, copies=1, visual=True)
        else:
            check_size(width, height)
            self._size = (width, height)

    def render(self, states: dict):
        """``states``: warpgym-layout arrays (root_pose, root_vel, dof_pos, dof_vel) of at least
        ``robots`` rows. Returns a tuple of frames (rgb_array) or None (human)."""
        if self.mode == "human":
            return self._show({k: np.asarray(states[k])[:1] for k in STATE_KEYS})
        if self._renderer is None:
            self._renderer = RobotRenderer(self.task, copies=1, width=self._size[0], height=self._size[1])
            self._open.hold(self._renderer)
        return tuple(self._renderer.render(*(np.asarray(states[k])[i : i + 1] for k in STATE_KEYS))
                     for i in range(self.robots))

    def _show(self, state: dict) -> None:
        import mujoco.viewer  # noqa: PLC0415

        self._robot.set_state(state["root_pose"], state["root_vel"], state["dof_pos"], state["dof_vel"])
        if self._viewer is None:
            self._viewer = mujoco.viewer.launch_passive(self._robot.model, self._robot.data[0])
            self._open.hold(self._viewer)
        self._viewer.sync()

    def close(self) -> None:
        self._open.close()
        self._renderer = self._viewer = None


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
        return write_clip(writers, strides, steps,
                          lambda t: renderer.render(*(np.asarray(states[k][t, :copies]) for k in STATE_KEYS)))


def clip_forward_speed(task, states: dict) -> np.ndarray:
    """(K,) forward speed of each robot over a clip (``StateRecorder.states()``): its travel between
    consecutive frames of one episode over their time (``LocomotionTask.forward_speed``). A reset inside
    the clip is not travel: the stride into a reset pose is left out, travel and time alike."""
    pos = states["root_pose"][..., :3]  # (T, K, 3)
    steps = states["episode_steps"]  # (T, K)
    same_episode = steps[1:] == steps[:-1] + 1
    travel = ((pos[1:] - pos[:-1]) * same_episode[..., None]).sum(axis=0)
    counted = same_episode.sum(axis=0)
    return np.where(counted > 0, task.forward_speed(travel, np.maximum(counted, 1)), 0.0)


def draw_robot_clip(env, states: dict, outputs: dict[str, dict], width: int, height: int) -> tuple[dict, dict]:
    """A clip of warpgym's robots (every recorded robot, a grid): (path -> frames written, what it measured)."""
    shown = states["root_pose"].shape[0] - 1  # steps after the first frame
    measured = {"clip/forward_speed": float(clip_forward_speed(env.task, states).mean())}
    print(f"clip: {shown} steps ({shown * env.task.dt:.1f} s) of {states['root_pose'].shape[1]} robot(s): forward "
          f"speed {measured['clip/forward_speed']:.2f} m/s")
    return render_clip(env.task, states, outputs, width, height), measured
