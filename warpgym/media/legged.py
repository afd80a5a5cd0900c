"""Frames and clips of the legged velocity tasks: the task's scene as MuJoCo compiles it (and its generated ground,
each patch coloured by its kind), drawn from MuJoCo's qpos of one world."""

from __future__ import annotations

import math

import numpy as np

from warpgym.media.ground_colours import colour_ground
from warpgym.media.render import Offscreen, check_size
from warpgym.media.video import real_time_writers, write_clip
from warpgym.tasks.legged.model import compile_task_scene


class LeggedView:
    """Draws one world of a legged task from MuJoCo's qpos: its collision geometry shown (the file holds no visual
    meshes), the camera following the base from behind and above."""

    def __init__(self, task, width: int = 640, height: int = 480):
        check_size(width, height)
        import mujoco  # noqa: PLC0415

        self._mj = mujoco
        self.task, self.width, self.height = task, width, height
        compiled, ground = compile_task_scene(task)
        self.model = compiled.mjm
        if ground is not None:
            colour_ground(self.model, ground)
        self.data = mujoco.MjData(self.model)
        self.root = self.model.body(task.root_body).id
        tall = self.model.body_subtreemass[self.root] > 20.0  # a humanoid rather than a quadruped
        self._frame = f = Offscreen(self.model, width, height)
        f.option.geomgroup[3] = 1  # the collision geoms: what the robot is made of in this scene
        f.camera.distance, f.camera.elevation = (3.0 if tall else 1.6), -15.0

    def render(self, qpos: np.ndarray) -> np.ndarray:
        mj, f = self._mj, self._frame
        self.data.qpos[:] = qpos
        mj.mj_kinematics(self.model, self.data)
        f.make_current()
        cam = f.camera
        cam.lookat[:] = self.data.xpos[self.root]
        # behind the base, as its heading turns
        x = self.data.xmat[self.root].reshape(3, 3)[:, 0]
        cam.azimuth = math.degrees(math.atan2(x[1], x[0])) + 150.0
        for _ in range(2):  # the first scene of a context draws a few levels off: twice
            mj.mjv_updateScene(self.model, self.data, f.option, f.perturb, cam, mj.mjtCatBit.mjCAT_ALL, f.scene)
            mj.mjr_render(f.rect, f.scene, f.gpu)
        return f.read()

    def close(self) -> None:
        self._frame.close()


def draw_legged_clip(env, states: dict, outputs: dict[str, dict], width: int, height: int) -> tuple[dict, dict]:
    """A clip of a legged task (its first world), in real time: (path -> frames, {})."""
    qpos = np.asarray(states["dof_pos"])
    shown = qpos.shape[0] - 1
    print(f"clip: {shown} steps ({shown * env.sim.dt:.1f} s) of one world")
    writers, strides = real_time_writers(outputs, env.sim.dt)
    view = LeggedView(env.task, width, height)
    try:
        return write_clip(writers, strides, qpos.shape[0],
                          lambda t: view.render(np.asarray(qpos[t][0], dtype=np.float64))), {}
    finally:
        view.close()
