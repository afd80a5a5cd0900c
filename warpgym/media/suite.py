"""Frames and clips of Gymnasium's MuJoCo tasks simulated by warpgym: the worlds' states copied into Gymnasium's own
env and drawn by its renderer, cameras and frame size."""

from __future__ import annotations

import os

import numpy as np

from warpgym.media.render import ClosedAtExit, check_size, check_view, gl_context
from warpgym.media.video import real_time_writers, write_clip


class SuiteView:
    """What Gymnasium's ``render()`` shows of one of its MuJoCo tasks simulated by warpgym.

    ``"rgb_array"``: a tuple of (height, width, 3) frames, one per world for the first ``robots``;
    ``"human"``: Gymnasium's viewer window on the first world (needs a display).

    ``follow``: keep the root body in the middle of the frame. Gymnasium 1.4's free camera stays where
    the robot started, so a runner leaves its frames within seconds; clips of the locomotion tasks follow.
    (Gymnasium 1.2 draws from the model's tracking camera, where a file has one, and follows anyway.)"""

    def __init__(self, task, mode: str, robots: int = 1, width: int = 640, height: int = 480,
                 follow: bool = False):
        check_view(mode, robots, "worlds")
        if mode == "rgb_array":
            check_size(width, height)
            if os.environ.get("MUJOCO_GL", "").strip().lower() not in ("egl", "osmesa"):
                # Gymnasium's renderer reads MUJOCO_GL when it makes its context: point it at a headless one
                context = gl_context(16, 16)
                os.environ["MUJOCO_GL"] = "egl" if type(context).__module__.endswith("egl") else "osmesa"
                context.free()
        import gymnasium  # noqa: PLC0415

        args = {name: getattr(task, name) for name in task.argument_names()}
        self.robots, self.mode, self.follow = robots, mode, follow
        self._env = gymnasium.make(task.gymnasium_id, render_mode=mode, width=width, height=height, **args).unwrapped
        self._open = ClosedAtExit()
        self._open.hold(self._env)

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
        self._open.close()
        self._env = None


def render_suite_clip(task, states: dict, outputs: dict[str, dict], dt: float, width: int = 640,
                      height: int = 480) -> dict[str, int]:
    """Draw the first world of a stored clip of one of Gymnasium's tasks (``dof_pos``, ``dof_vel``: MuJoCo's
    qpos and qvel, (steps, worlds, n)) with Gymnasium's own renderer of the task, into each output
    (path -> ``{"fps": ..., "width": ...}``), in real time, the camera following the root body where the task says so
    (``camera_follows``: the runners). Returns path -> frames written."""
    missing = [k for k in ("dof_pos", "dof_vel") if k not in states]
    if missing:
        raise ValueError(f"states lack {missing}: a clip of a suite task needs MuJoCo's qpos and qvel")
    writers, strides = real_time_writers(outputs, dt)
    view = SuiteView(task, "rgb_array", 1, width, height, follow=task.camera_follows)
    try:
        return write_clip(writers, strides, np.asarray(states["dof_pos"]).shape[0],
                          lambda t: view.render(np.asarray(states["dof_pos"][t], dtype=np.float64),
                                                np.asarray(states["dof_vel"][t], dtype=np.float64))[0])
    finally:
        view.close()


def draw_suite_clip(env, states: dict, outputs: dict[str, dict], width: int, height: int) -> tuple[dict, dict]:
    """A clip of one of Gymnasium's tasks (its first world, Gymnasium's renderer): (path -> frames, {})."""
    shown = states["dof_pos"].shape[0] - 1
    print(f"clip: {shown} steps ({shown * env.sim.dt:.1f} s) of one world")
    return render_suite_clip(env.task, states, outputs, env.sim.dt, width, height), {}
