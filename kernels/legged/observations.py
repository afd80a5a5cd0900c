"""The observation terms of the legged velocity tasks (mjlab's velocity config, "actor" and "critic" groups), one
Warp function each, entry by entry: ``(env: LeggedEnv, w: int, i: int[, p: Params]) -> float``. A task's tables
(``warpgym.tasks.legged.base``) list them in order with their sizes, noise and scales: the base's velocities from
the IMU sensors, gravity in the base's frame, joint positions (the policy's through the randomised encoder bias)
and velocities, the last action, the command; the critic also the feet's heights, air times, contacts and contact
forces, and neither noise nor bias.

On rough ground both also see the height scan (the base's height above the ground under a grid of rays, after
the command; the policy's with noise), and the feet's heights are the foot height scan's (``kernels.legged.scan``:
a ring of rays cast down from each foot). On the flat floor at z = 0 every ray of a ring hits at the site's own
height, so the scan is the site's height clamped into [0, range], which is what ``foot_height`` computes.
"""

import warp as wp

from kernels.legged.frames import projected_gravity
from kernels.legged.params import LeggedEnv, MjLegged

wp.set_module_options({"enable_backward": False})

# the scan's reach [m] (mjlab's foot_height_scan max_distance)
FOOT_SCAN_RANGE = 1.0


@wp.func
def foot_height(d: MjLegged, w: int, site: int):
    return wp.clamp(d.site_xpos[w, site][2], 0.0, FOOT_SCAN_RANGE)


@wp.func
def signed_log(x: float):
    return wp.sign(x) * wp.log(1.0 + wp.abs(x))


# Observation terms: (env, w, i[, p]) -> float, entry i of the term for world w; a task's table
# (warpgym.tasks.terms.Observation) gives each its size, noise, clip and scale.


@wp.struct
class Encoder:
    biased: int  # 1: read through the world's randomised encoder bias (the policy's), 0: the true position


@wp.func
def base_lin_vel(env: LeggedEnv, w: int, i: int) -> float:
    """the base's linear velocity in its own frame, from its IMU [m/s]"""
    return env.d.sensordata[w, env.r.imu_lin_vel + i]


@wp.func
def base_ang_vel(env: LeggedEnv, w: int, i: int) -> float:
    """the base's angular velocity in its own frame, from its IMU [rad/s]"""
    return env.d.sensordata[w, env.r.imu_ang_vel + i]


@wp.func
def gravity(env: LeggedEnv, w: int, i: int) -> float:
    """the unit gravity vector in the base's frame"""
    return projected_gravity(env.d.xquat[w, env.r.root_body])[i]


@wp.func
def joint_pos(env: LeggedEnv, w: int, i: int, p: Encoder) -> float:
    """each joint's position minus its default [rad]"""
    q = env.d.qpos[w, env.r.joint_qpos[i]]
    if p.biased != 0:  # mjlab adds the bias to the position before taking the default away
        q = q + env.st.encoder_bias[w, i]
    return q - env.r.default_joint_pos[i]


@wp.func
def joint_vel(env: LeggedEnv, w: int, i: int) -> float:
    """each joint's velocity [rad/s]"""
    return env.d.qvel[w, env.r.joint_dof[i]]


@wp.func
def last_action(env: LeggedEnv, w: int, i: int) -> float:
    """the previous action, as the policy gave it"""
    return env.st.action[w, i]


@wp.func
def velocity_command(env: LeggedEnv, w: int, i: int) -> float:
    """the velocity command: forward, sideways [m/s], yaw rate [rad/s], in the base's frame"""
    return env.st.command[w, i]


@wp.func
def height_scan(env: LeggedEnv, w: int, i: int) -> float:
    """the base's height above each ray's hit (a miss reads the reach), the rays under the base and turned with
    its heading [m]"""
    return env.st.scan[w, i]


@wp.func
def foot_height_now(env: LeggedEnv, w: int, f: int):
    """A foot's height: scanned on rough ground (the scan this observation made), the site's on the flat floor."""
    if env.p.foot_scan != 0:
        return env.st.foot_clear[w, f]
    return foot_height(env.d, w, env.r.foot_site[f])


@wp.func
def feet_height(env: LeggedEnv, w: int, i: int) -> float:
    """each foot's height above the ground [m]"""
    return foot_height_now(env, w, i)


@wp.func
def feet_air_time(env: LeggedEnv, w: int, i: int) -> float:
    """how long each foot has been off the ground [s]"""
    return env.st.air_time[w, i]


@wp.func
def feet_contact(env: LeggedEnv, w: int, i: int) -> float:
    """1 where a foot touches the ground, else 0"""
    if env.d.sensordata[w, env.r.foot_found[i]] > 0.0:
        return 1.0
    return 0.0


@wp.func
def feet_contact_forces(env: LeggedEnv, w: int, i: int) -> float:
    """each foot's net contact force (world frame), sign x log(1 + |f|), three entries a foot"""
    return signed_log(env.d.sensordata[w, env.r.foot_force[i / 3] + i % 3])
