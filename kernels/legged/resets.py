"""mjlab's reset of the worlds whose episode ended (its reset events, the sensors' and managers' resets), and the
randomisation it draws once per world when the env is built (its startup events).

A reset world starts from its default pose (the scene's keyframe) at its start on the ground, moved by a uniform offset in x, y, z and yaw,
its joints at their defaults (plus mjlab's offset range, 0 in its config) clamped into the soft limits, at rest,
with zero controls and a fresh solver warm start (MuJoCo Warp's reset_data zeroes them too); its action history,
air and contact times and tracking errors restart, it draws a new command and a new time to its next push. The
swing heights' peaks are not reset: mjlab's swing-height term keeps them across episodes.
"""

import warp as wp

from kernels.common import StepOutputs, resets_world, stream
from kernels.legged.commands import draw_command
from kernels.legged.params import NUM_GROUPS, LeggedEpisodes, LeggedParams, LeggedRobot, LeggedState, MjLegged
from kernels.legged.random import RESET, STARTUP

wp.set_module_options({"enable_backward": False})


@wp.kernel
def reset_legged_worlds(p: LeggedParams, r: LeggedRobot, force_all: int, stagger: int,
                        rng_state: wp.array[wp.int32], origin: wp.array[wp.vec3], d: MjLegged, st: LeggedState,
                        ep: LeggedEpisodes, out: StepOutputs):
    """``origin``: each world's start on the ground (its terrain patch's; zero on flat ground)."""
    w = wp.tid()
    if not resets_world(force_all, out, w):
        return
    rng = stream(rng_state, w, RESET)
    a = r.root_qpos
    for i in range(3):
        d.qpos[w, a + i] = r.default_root[i] + origin[w][i] + wp.randf(rng, p.reset_lo[i], p.reset_hi[i])
    yaw = wp.randf(rng, p.reset_lo[3], p.reset_hi[3])
    turn = wp.quat(wp.cos(0.5 * yaw), 0.0, 0.0, wp.sin(0.5 * yaw))
    base = wp.quat(r.default_root[3], r.default_root[4], r.default_root[5], r.default_root[6])
    # the Hamilton product base * turn, (w, x, y, z) as mjlab's quat_mul computes it
    qw = base[0] * turn[0] - base[1] * turn[1] - base[2] * turn[2] - base[3] * turn[3]
    qx = base[0] * turn[1] + base[1] * turn[0] + base[2] * turn[3] - base[3] * turn[2]
    qy = base[0] * turn[2] - base[1] * turn[3] + base[2] * turn[0] + base[3] * turn[1]
    qz = base[0] * turn[3] + base[1] * turn[2] - base[2] * turn[1] + base[3] * turn[0]
    d.qpos[w, a + 3] = qw
    d.qpos[w, a + 4] = qx
    d.qpos[w, a + 5] = qy
    d.qpos[w, a + 6] = qz
    for i in range(d.qvel.shape[1]):
        d.qvel[w, i] = 0.0
        d.warm_start[w, i] = 0.0
    for j in range(r.joint_qpos.shape[0]):
        q = r.default_joint_pos[j] + wp.randf(rng, p.joint_pos_offset_lo, p.joint_pos_offset_hi)
        d.qpos[w, r.joint_qpos[j]] = wp.clamp(q, r.soft_lo[j], r.soft_hi[j])
        d.qvel[w, r.joint_dof[j]] = wp.randf(rng, p.joint_vel_lo, p.joint_vel_hi)
    for u in range(d.ctrl.shape[1]):
        d.ctrl[w, u] = 0.0
    for i in range(st.action.shape[1]):
        st.action[w, i] = 0.0
        st.prev_action[w, i] = 0.0
    for f in range(st.air_time.shape[1]):
        st.air_time[w, f] = 0.0
        st.contact_time[w, f] = 0.0
    for g in range(NUM_GROUPS):
        st.collision_hits[w, g] = 0
    st.fresh[w] = 1
    rng = draw_command(p, st, w, rng)
    st.push_time_left[w] = wp.randf(rng, p.push_interval_lo, p.push_interval_hi)
    ep.length[w] = 0
    if force_all != 0 and stagger != 0:  # rsl_rl's init_at_random_ep_len: the time limits fall apart
        ep.length[w] = wp.int32(wp.randi(rng, 0, p.episode_length))
    ep.total_return[w] = 0.0
    ep.errors[w, 0] = 0.0
    ep.errors[w, 1] = 0.0


@wp.struct
class Randomization:
    """mjlab's startup events: friction of the feet (per axis, one draw a world shared by all foot geoms, uniform
    or log-uniform), an offset of one body's centre of mass, the joint encoders' bias."""

    foot_geoms: wp.array[wp.int32]  # (G,)
    friction_axis: wp.array[wp.int32]  # (X,) the friction axes drawn (0 sliding, 1 torsional, 2 rolling)
    friction_lo: wp.array[float]  # (X,)
    friction_hi: wp.array[float]
    friction_log: wp.array[wp.int32]  # (X,) 1: log-uniform
    com_body: int
    com_lo: wp.vec3
    com_hi: wp.vec3
    bias_lo: float
    bias_hi: float


@wp.kernel
def randomize_worlds(rz: Randomization, rng_state: wp.array[wp.int32], default_ipos: wp.vec3,
                     geom_friction: wp.array2d[wp.vec3], body_ipos: wp.array2d[wp.vec3],
                     encoder_bias: wp.array2d[float]):
    w = wp.tid()
    rng = stream(rng_state, w, STARTUP)
    for x in range(rz.friction_axis.shape[0]):
        lo = rz.friction_lo[x]
        hi = rz.friction_hi[x]
        value = float(0.0)
        if rz.friction_log[x] != 0:
            value = wp.exp(wp.randf(rng, wp.log(lo), wp.log(hi)))
        else:
            value = wp.randf(rng, lo, hi)
        axis = rz.friction_axis[x]
        for g in range(rz.foot_geoms.shape[0]):
            f = geom_friction[w, rz.foot_geoms[g]]
            f[axis] = value
            geom_friction[w, rz.foot_geoms[g]] = f
    offset = wp.vec3(wp.randf(rng, rz.com_lo[0], rz.com_hi[0]), wp.randf(rng, rz.com_lo[1], rz.com_hi[1]),
                     wp.randf(rng, rz.com_lo[2], rz.com_hi[2]))
    body_ipos[w, rz.com_body] = default_ipos + offset
    for j in range(encoder_bias.shape[1]):
        encoder_bias[w, j] = wp.randf(rng, rz.bias_lo, rz.bias_hi)
