"""mjlab's event terms of the velocity tasks, one Warp function each: ``(env: LeggedEnv, w: int, rng: wp.uint32[,
p: Params]) -> wp.uint32``, which changes world ``w`` (its MuJoCo state, its randomised model fields ``env.m``, its
task state) drawing from ``rng``, and returns the random state after its draws. A task's table
(``warpgym.tasks.terms.Event``) says when each runs: at the world's reset, on a timer, or once when the env is built.
A ``wp.vec2`` parameter is a (low, high) range.

A user's own event is a function of this form in their own module.
"""

import warp as wp

from kernels.legged.frames import angular_velocity, point_velocity, rotate_inverse
from kernels.legged.params import LeggedEnv

wp.set_module_options({"enable_backward": False})


@wp.struct
class RootPose:
    x: wp.vec2  # offsets of the default root position [m]
    y: wp.vec2
    z: wp.vec2
    yaw: wp.vec2  # [rad]


@wp.func
def reset_root_pose(env: LeggedEnv, w: int, rng: wp.uint32, p: RootPose) -> wp.uint32:
    """mjlab's reset_root_state_uniform: the default root pose (the scene's keyframe) at the world's start on the
    ground, moved by a uniform offset in x, y and z and turned by a uniform yaw."""
    r = env.r
    a = r.root_qpos
    origin = env.t.origin[w]
    env.d.qpos[w, a] = r.default_root[0] + origin[0] + wp.randf(rng, p.x[0], p.x[1])
    env.d.qpos[w, a + 1] = r.default_root[1] + origin[1] + wp.randf(rng, p.y[0], p.y[1])
    env.d.qpos[w, a + 2] = r.default_root[2] + origin[2] + wp.randf(rng, p.z[0], p.z[1])
    yaw = wp.randf(rng, p.yaw[0], p.yaw[1])
    turn = wp.quat(wp.cos(0.5 * yaw), 0.0, 0.0, wp.sin(0.5 * yaw))
    base = wp.quat(r.default_root[3], r.default_root[4], r.default_root[5], r.default_root[6])
    # the Hamilton product base * turn, (w, x, y, z) as mjlab's quat_mul computes it
    env.d.qpos[w, a + 3] = base[0] * turn[0] - base[1] * turn[1] - base[2] * turn[2] - base[3] * turn[3]
    env.d.qpos[w, a + 4] = base[0] * turn[1] + base[1] * turn[0] + base[2] * turn[3] - base[3] * turn[2]
    env.d.qpos[w, a + 5] = base[0] * turn[2] - base[1] * turn[3] + base[2] * turn[0] + base[3] * turn[1]
    env.d.qpos[w, a + 6] = base[0] * turn[3] + base[1] * turn[2] - base[2] * turn[1] + base[3] * turn[0]
    return rng


@wp.struct
class JointOffsets:
    position: wp.vec2  # added to each joint's default position [rad], then clamped into the soft limits
    velocity: wp.vec2  # each joint's velocity [rad/s]


@wp.func
def reset_joints_by_offset(env: LeggedEnv, w: int, rng: wp.uint32, p: JointOffsets) -> wp.uint32:
    """mjlab's reset_joints_by_offset: each joint at its default position plus a uniform offset, clamped into its
    soft limits, with a uniform velocity."""
    r = env.r
    for j in range(r.joint_qpos.shape[0]):
        q = r.default_joint_pos[j] + wp.randf(rng, p.position[0], p.position[1])
        env.d.qpos[w, r.joint_qpos[j]] = wp.clamp(q, r.soft_lo[j], r.soft_hi[j])
        env.d.qvel[w, r.joint_dof[j]] = wp.randf(rng, p.velocity[0], p.velocity[1])
    return rng


@wp.struct
class PushVelocity:
    x: wp.vec2  # added to the base's linear velocity, world frame [m/s]
    y: wp.vec2
    z: wp.vec2
    roll: wp.vec2  # ... to its angular velocity, world frame [rad/s]
    pitch: wp.vec2
    yaw: wp.vec2


@wp.func
def push_by_setting_velocity(env: LeggedEnv, w: int, rng: wp.uint32, p: PushVelocity) -> wp.uint32:
    """mjlab's push_by_setting_velocity: the base's world velocity (from the last forward pass) plus a uniform
    draw, written into the free joint's qvel (linear in the world frame, angular in the base's, through the
    orientation in qpos)."""
    r = env.r
    d = env.d
    root = r.root_body
    lin = point_velocity(d, w, root, root, d.xpos[w, root])
    ang = angular_velocity(d, w, root)
    lin = lin + wp.vec3(wp.randf(rng, p.x[0], p.x[1]), wp.randf(rng, p.y[0], p.y[1]), wp.randf(rng, p.z[0], p.z[1]))
    ang = ang + wp.vec3(wp.randf(rng, p.roll[0], p.roll[1]), wp.randf(rng, p.pitch[0], p.pitch[1]),
                        wp.randf(rng, p.yaw[0], p.yaw[1]))
    a = r.root_qpos + 3
    q = wp.quat(d.qpos[w, a], d.qpos[w, a + 1], d.qpos[w, a + 2], d.qpos[w, a + 3])
    ang_b = rotate_inverse(q, ang)
    for i in range(3):
        d.qvel[w, r.root_dof + i] = lin[i]
        d.qvel[w, r.root_dof + 3 + i] = ang_b[i]
    return rng


@wp.struct
class FootFriction:
    axis: int  # 0 sliding, 1 torsional, 2 rolling
    value: wp.vec2  # the coefficient's range
    log_uniform: int  # 1: drawn log-uniformly, else uniformly


@wp.func
def randomize_foot_friction(env: LeggedEnv, w: int, rng: wp.uint32, p: FootFriction) -> wp.uint32:
    """mjlab's randomize_field on geom_friction: one draw a world of one friction axis, shared by every foot geom."""
    value = float(0.0)
    if p.log_uniform != 0:
        value = wp.exp(wp.randf(rng, wp.log(p.value[0]), wp.log(p.value[1])))
    else:
        value = wp.randf(rng, p.value[0], p.value[1])
    for g in range(env.r.foot_geom.shape[0]):
        f = env.m.geom_friction[w, env.r.foot_geom[g]]
        f[p.axis] = value
        env.m.geom_friction[w, env.r.foot_geom[g]] = f
    return rng


@wp.struct
class ComOffset:
    x: wp.vec2  # added to the compiled centre of mass of the task's com_body, in the body's frame [m]
    y: wp.vec2
    z: wp.vec2


@wp.func
def randomize_com(env: LeggedEnv, w: int, rng: wp.uint32, p: ComOffset) -> wp.uint32:
    """mjlab's randomize_field on body_ipos ("add"): the task's com_body's centre of mass moved by a uniform
    offset from the compiled one."""
    b = env.r.com_body
    offset = wp.vec3(wp.randf(rng, p.x[0], p.x[1]), wp.randf(rng, p.y[0], p.y[1]), wp.randf(rng, p.z[0], p.z[1]))
    env.m.body_ipos[w, b] = env.m.body_ipos0[b] + offset
    return rng


@wp.struct
class EncoderBias:
    bias: wp.vec2  # [rad]


@wp.func
def randomize_encoder_bias(env: LeggedEnv, w: int, rng: wp.uint32, p: EncoderBias) -> wp.uint32:
    """mjlab's encoder bias: a uniform offset per joint, added to the joint position the policy reads and taken
    off the target it sends."""
    for j in range(env.st.encoder_bias.shape[1]):
        env.st.encoder_bias[w, j] = wp.randf(rng, p.bias[0], p.bias[1])
    return rng
