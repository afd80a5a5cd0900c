"""The locomotion observation (Isaac Gym's Ant and Humanoid layout), written row by row.

Row layout for A actuated dofs and F feet:
    0 torso height | 1:4 vel_loc | 4:7 angvel_loc * s | 7 yaw | 8 roll | 9 angle_to_target
    10 up_proj | 11 heading_proj | dof_pos_scaled (A) | dof_vel * s (A)
    [dof_force * s (A), when observed] | foot force 3 + torque 3 * s (6F) | last actions (A)
"""

import warp as wp

from kernels.robots.buffers import RobotView
from kernels.math import finite_or_zero, roll_from_quat, unscale, wrap_angle, yaw_from_quat
from kernels.robots.params import LocomotionParams
from kernels.tensor_api import ROOT_COORDS, ROOT_DOFS


@wp.func
def root_position(joint_q: wp.array2d[float], env: int):
    return wp.vec3(joint_q[env, 0], joint_q[env, 1], joint_q[env, 2])


@wp.func
def root_rotation(joint_q: wp.array2d[float], env: int):
    return wp.quat(joint_q[env, 3], joint_q[env, 4], joint_q[env, 5], joint_q[env, 6])


@wp.func
def target_offset(p: LocomotionParams, pos: wp.vec3):
    # horizontal vector from the torso to the walk target
    d = p.target - pos
    return wp.vec3(d[0], d[1], 0.0)


@wp.func
def potential(p: LocomotionParams, pos: wp.vec3):
    return -wp.length(target_offset(p, pos)) / p.dt


@wp.func
def forward_speed(p: LocomotionParams, pos: wp.vec3, steps: int):
    # The project's one forward speed: the root's travel from the start pose along the task's forward
    # direction, over the time the episode has lasted (LocomotionTask.forward_speed is its host twin).
    travel = wp.dot(pos - p.start_pos, p.forward_dir)
    return travel / (float(wp.max(steps, 1)) * p.dt)


@wp.func
def write_observation(
    env: int,
    p: LocomotionParams,
    robot: RobotView,
    fresh: int,  # 1 right after a reset: no forces have acted and no action was taken yet
    obs: wp.array2d[float],  # (N, O) out
):
    joint_q = robot.joint_q
    joint_qd = robot.joint_qd
    num_dofs = robot.actions.shape[1]
    pos = root_position(joint_q, env)
    torso_quat = root_rotation(joint_q, env) * wp.quat_inverse(p.start_rot)
    lin_vel = wp.vec3(joint_qd[env, 0], joint_qd[env, 1], joint_qd[env, 2])
    ang_vel = wp.vec3(joint_qd[env, 3], joint_qd[env, 4], joint_qd[env, 5])

    to_target = target_offset(p, pos)
    up_vec = wp.quat_rotate(torso_quat, wp.vec3(0.0, 0.0, 1.0))
    heading_vec = wp.quat_rotate(torso_quat, wp.vec3(1.0, 0.0, 0.0))
    vel_loc = wp.quat_rotate_inv(torso_quat, lin_vel)
    angvel_loc = wp.quat_rotate_inv(torso_quat, ang_vel) * p.angular_velocity_scale
    yaw = yaw_from_quat(torso_quat)

    obs[env, 0] = finite_or_zero(pos[2])
    for i in range(3):
        obs[env, 1 + i] = finite_or_zero(vel_loc[i])
        obs[env, 4 + i] = finite_or_zero(angvel_loc[i])
    obs[env, 7] = finite_or_zero(yaw)
    obs[env, 8] = finite_or_zero(roll_from_quat(torso_quat))
    obs[env, 9] = finite_or_zero(wrap_angle(wp.atan2(to_target[1], to_target[0]) - yaw))
    obs[env, 10] = finite_or_zero(up_vec[2])
    obs[env, 11] = finite_or_zero(wp.dot(heading_vec, wp.normalize(to_target)))

    col = int(12)
    for j in range(num_dofs):
        q = joint_q[env, ROOT_COORDS + j]
        obs[env, col + j] = finite_or_zero(unscale(q, robot.dof_lower[j], robot.dof_upper[j]))
    col += num_dofs
    for j in range(num_dofs):
        obs[env, col + j] = finite_or_zero(joint_qd[env, ROOT_DOFS + j] * p.dof_velocity_scale)
    col += num_dofs
    if p.observe_dof_forces != 0:
        for j in range(num_dofs):
            f = float(0.0)
            if fresh == 0:
                f = robot.dof_force[env, j] * p.dof_force_scale
            obs[env, col + j] = finite_or_zero(f)
        col += num_dofs
    num_feet = robot.foot_bodies.shape[0]
    for k in range(num_feet):
        row = env * robot.bodies_per_env + robot.foot_bodies[k]
        for i in range(6):
            w = float(0.0)
            if fresh == 0:
                w = robot.contact_wrench[row, i] * p.contact_force_scale
            obs[env, col + 6 * k + i] = finite_or_zero(w)
    col += 6 * num_feet
    for j in range(num_dofs):
        a = float(0.0)
        if fresh == 0:
            a = robot.actions[env, j]
        obs[env, col + j] = a
