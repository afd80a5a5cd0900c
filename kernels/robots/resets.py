"""Masked reset of the locomotion envs that finished, inside the same step (same-step autoreset)."""

import warp as wp

from kernels.common import StepOutputs, env_rng, resets_world
from kernels.robots.buffers import EpisodeBuffers, RobotView
from kernels.robots.observations import potential, write_observation
from kernels.robots.params import LocomotionParams
from kernels.tensor_api import ROOT_COORDS, ROOT_DOFS

# Nothing differentiates through these kernels; skipping adjoint code shortens their compile.
wp.set_module_options({"enable_backward": False})


@wp.func
def draw_start_state(env: int, p: LocomotionParams, robot: RobotView, rng_state: wp.array[wp.int32]):
    rng = env_rng(rng_state, env)
    for i in range(3):
        robot.joint_q[env, i] = p.start_pos[i]
    for i in range(4):
        robot.joint_q[env, 3 + i] = p.start_rot[i]
    for i in range(ROOT_DOFS):
        robot.joint_qd[env, i] = 0.0
    for j in range(robot.default_dof_pos.shape[0]):
        q = robot.default_dof_pos[j] + wp.randf(rng, -p.dof_pos_noise, p.dof_pos_noise)
        robot.joint_q[env, ROOT_COORDS + j] = wp.clamp(q, robot.dof_lower[j], robot.dof_upper[j])
        robot.joint_qd[env, ROOT_DOFS + j] = wp.randf(rng, -p.dof_vel_noise, p.dof_vel_noise)
    for j in range(robot.warm_start.shape[1]):
        robot.warm_start[env, j] = 0.0


@wp.kernel
def reset_finished_envs(
    p: LocomotionParams,
    force_all: int,  # 1: reset every env and record nothing (an explicit reset())
    rng_state: wp.array[wp.int32],  # (2,) seed, step counter
    robot: RobotView,
    episodes: EpisodeBuffers,
    out: StepOutputs,
):
    env = wp.tid()
    if not resets_world(force_all, out, env):
        return
    episodes.length[env] = 0
    episodes.total_return[env] = 0.0
    episodes.speed[env] = 0.0
    draw_start_state(env, p, robot, rng_state)
    episodes.potential[env] = potential(p, p.start_pos)
    write_observation(env, p, robot, 1, out.obs)
