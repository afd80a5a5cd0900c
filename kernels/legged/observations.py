"""What the policy and the critic see (mjlab's velocity config, "actor" and "critic" groups), written once per
world: the base's velocities from the IMU sensors, gravity in the base's frame, joint positions (the policy's
through the randomised encoder bias) and velocities, the last action, the command; the critic also the feet's
heights, air times, contacts and contact forces, and neither noise nor bias.

On rough ground both also see the height scan (the base's height above the ground under a grid of rays, after
the command; the policy's with noise), and the feet's heights are the foot height scan's (``kernels.legged.scan``:
a ring of rays cast down from each foot). On the flat floor at z = 0 every ray of a ring hits at the site's own
height, so the scan is the site's height clamped into [0, range], which is what ``foot_height`` computes.
"""

import warp as wp

from kernels.common import stream
from kernels.legged.frames import projected_gravity, sensor3
from kernels.legged.params import LeggedParams, LeggedRobot, LeggedState, MjLegged
from kernels.legged.random import OBSERVATION

wp.set_module_options({"enable_backward": False})

# the scan's reach [m] (mjlab's foot_height_scan max_distance)
FOOT_SCAN_RANGE = 1.0


@wp.func
def foot_height(d: MjLegged, w: int, site: int):
    return wp.clamp(d.site_xpos[w, site][2], 0.0, FOOT_SCAN_RANGE)


@wp.func
def foot_height_now(p: LeggedParams, r: LeggedRobot, d: MjLegged, st: LeggedState, w: int, f: int):
    """A foot's height: scanned on rough ground (the scan this observation made), the site's on the flat floor."""
    if p.foot_scan != 0:
        return st.foot_clear[w, f]
    return foot_height(d, w, r.foot_site[f])


@wp.func
def signed_log(x: float):
    return wp.sign(x) * wp.log(1.0 + wp.abs(x))


@wp.func
def write_observation(p: LeggedParams, r: LeggedRobot, d: MjLegged, st: LeggedState, w: int, rng: wp.uint32,
                      actor: wp.array2d[float], critic: wp.array2d[float]):
    """The policy's (``actor``, with noise) and the critic's observation of world ``w`` from MuJoCo's data as it
    is now. (Warp's random draws advance the state they are given in place: ``rng`` is drawn from here directly,
    never through a helper function, which would draw from a copy.)"""
    lin = sensor3(d, w, r.imu_lin_vel)
    ang = sensor3(d, w, r.imu_ang_vel)
    g = projected_gravity(d.xquat[w, r.root_body])
    for i in range(3):
        actor[w, i] = lin[i] + wp.randf(rng, -p.noise_lin_vel, p.noise_lin_vel)
        actor[w, 3 + i] = ang[i] + wp.randf(rng, -p.noise_ang_vel, p.noise_ang_vel)
        actor[w, 6 + i] = g[i] + wp.randf(rng, -p.noise_gravity, p.noise_gravity)
        critic[w, i] = lin[i]
        critic[w, 3 + i] = ang[i]
        critic[w, 6 + i] = g[i]
    nj = r.joint_qpos.shape[0]
    k = int(9)
    for j in range(nj):
        rel = d.qpos[w, r.joint_qpos[j]] - r.default_joint_pos[j]
        # mjlab adds the bias to the position before taking the default away
        biased = d.qpos[w, r.joint_qpos[j]] + st.encoder_bias[w, j] - r.default_joint_pos[j]
        actor[w, k + j] = biased + wp.randf(rng, -p.noise_joint_pos, p.noise_joint_pos)
        critic[w, k + j] = rel
        vel = d.qvel[w, r.joint_dof[j]]
        actor[w, k + nj + j] = vel + wp.randf(rng, -p.noise_joint_vel, p.noise_joint_vel)
        critic[w, k + nj + j] = vel
    k = k + 2 * nj
    na = st.action.shape[1]
    for a in range(na):
        actor[w, k + a] = st.action[w, a]
        critic[w, k + a] = st.action[w, a]
    k = k + na
    for i in range(3):
        actor[w, k + i] = st.command[w, i]
        critic[w, k + i] = st.command[w, i]
    k = k + 3
    for i in range(p.num_scan):
        h = st.scan[w, i]
        actor[w, k + i] = (h + wp.randf(rng, -p.noise_scan, p.noise_scan)) * p.scan_scale
        critic[w, k + i] = h * p.scan_scale
    k = k + p.num_scan
    nf = r.foot_site.shape[0]
    for f in range(nf):
        critic[w, k + f] = foot_height_now(p, r, d, st, w, f)
        critic[w, k + nf + f] = st.air_time[w, f]
        contact = float(0.0)
        if d.sensordata[w, r.foot_found[f]] > 0.0:
            contact = 1.0
        critic[w, k + 2 * nf + f] = contact
        force = sensor3(d, w, r.foot_force[f])
        for i in range(3):
            critic[w, k + 3 * nf + 3 * f + i] = signed_log(force[i])


@wp.kernel
def observe(p: LeggedParams, r: LeggedRobot, rng_state: wp.array[wp.int32], d: MjLegged, st: LeggedState,
            actor: wp.array2d[float], critic: wp.array2d[float]):
    """mjlab's sense and observation pass after the step's forward pass (and, on rough ground, the scans): the
    feet's heights, kept for the next step's rewards, and both observations."""
    w = wp.tid()
    for f in range(r.foot_site.shape[0]):
        st.foot_height[w, f] = foot_height_now(p, r, d, st, w, f)
    write_observation(p, r, d, st, w, stream(rng_state, w, OBSERVATION), actor, critic)
