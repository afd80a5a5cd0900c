"""mjlab's reward terms of the velocity tasks, one Warp function each: ``(env: LeggedEnv, w: int[, p: Params]) ->
float``, the unweighted value of world ``w``, read from the data as the step's last physics step left it (body
frames, com velocities, site positions and sensor data one physics step behind the state, as mjlab reads them; the
feet's heights those of the last observation). A term's parameters are the fields of the struct its third argument
names; a task's table (``warpgym.tasks.terms.Reward``) gives them by name, with the term's weight.

A user's own reward term is a function of this form in their own module.
"""

import warp as wp

from kernels.legged.frames import angular_velocity, point_velocity, projected_gravity, rotate_inverse, root_velocity_b, sensor3
from kernels.legged.params import LeggedEnv

wp.set_module_options({"enable_backward": False})


@wp.struct
class Std:
    std: float  # the Gaussian kernel's width


@wp.struct
class Upright:
    std: float
    on_terrain: int  # 1: "up" is the ground's normal under the height scan (the rough Go1's), else the world's z


@wp.struct
class Posture:
    std_standing: wp.array[float]  # (J,) each joint's std while the command's speed is under walking_threshold
    std_walking: wp.array[float]  # (J,) ... under running_threshold
    std_running: wp.array[float]  # (J,) ... above it
    walking_threshold: float
    running_threshold: float


@wp.struct
class AirTime:
    threshold_min: float  # a foot's air time between these scores 1 [s]
    threshold_max: float
    command_threshold: float  # only while the command's speed exceeds this


@wp.struct
class FootHeight:
    target_height: float  # [m]
    command_threshold: float


@wp.struct
class Moving:
    command_threshold: float  # the term counts only while the command's speed exceeds this


@wp.struct
class ContactGroup:
    group: int  # kernels.legged.params: SELF_COLLISION, SHANK_GROUND, TRUNK_GROUND


@wp.func
def command_speed(env: LeggedEnv, w: int):
    """|v_xy| + |yaw rate| of the command in force."""
    c = env.st.command
    return wp.sqrt(c[w, 0] * c[w, 0] + c[w, 1] * c[w, 1]) + wp.abs(c[w, 2])


@wp.func
def moving(env: LeggedEnv, w: int, threshold: float):
    """1 while the command's speed exceeds ``threshold``, else 0."""
    if command_speed(env, w) > threshold:
        return 1.0
    return 0.0


@wp.func
def in_contact(env: LeggedEnv, w: int, f: int):
    return env.d.sensordata[w, env.r.foot_found[f]] > 0.0


@wp.func
def first_contact(env: LeggedEnv, w: int, f: int):
    """A foot that landed within this control step (mjlab's compute_first_contact)."""
    t = env.st.contact_time[w, f]
    return t > 0.0 and t < env.p.dt + 1.0e-6


@wp.func
def foot_velocity(env: LeggedEnv, w: int, f: int):
    r = env.r
    return point_velocity(env.d, w, r.foot_body[f], r.root_body, env.d.site_xpos[w, r.foot_site[f]])


@wp.func
def track_linear_velocity(env: LeggedEnv, w: int, p: Std) -> float:
    """exp(-(|command_xy - v_xy|^2 + v_z^2) / std^2), the base's velocity in its own frame."""
    v, omega = root_velocity_b(env.d, env.r, w)
    ex = env.st.command[w, 0] - v[0]
    ey = env.st.command[w, 1] - v[1]
    return wp.exp(-(ex * ex + ey * ey + v[2] * v[2]) / (p.std * p.std))


@wp.func
def track_angular_velocity(env: LeggedEnv, w: int, p: Std) -> float:
    """exp(-((command_yaw - omega_z)^2 + omega_x^2 + omega_y^2) / std^2)."""
    v, omega = root_velocity_b(env.d, env.r, w)
    ez = env.st.command[w, 2] - omega[2]
    return wp.exp(-(ez * ez + omega[0] * omega[0] + omega[1] * omega[1]) / (p.std * p.std))


@wp.func
def upright(env: LeggedEnv, w: int, p: Upright) -> float:
    """exp(-|g_xy|^2 / std^2), g the upright body's "up" (world z, or the ground's normal) in its own frame."""
    q = env.d.xquat[w, env.r.upright_body]
    g = projected_gravity(q)
    if p.on_terrain != 0:  # the ground's normal in the body's frame: (0, 0, 1) when level with it
        g = rotate_inverse(q, env.st.terrain_normal[w])
    return wp.exp(-(g[0] * g[0] + g[1] * g[1]) / (p.std * p.std))


@wp.func
def pose(env: LeggedEnv, w: int, p: Posture) -> float:
    """exp(-mean over joints of (q - default)^2 / std^2), each joint's std by the command's speed."""
    speed = command_speed(env, w)
    r = env.r
    total = float(0.0)
    nj = r.joint_qpos.shape[0]
    for j in range(nj):
        std = p.std_running[j]
        if speed < p.walking_threshold:
            std = p.std_standing[j]
        elif speed < p.running_threshold:
            std = p.std_walking[j]
        e = env.d.qpos[w, r.joint_qpos[j]] - r.default_joint_pos[j]
        total += e * e / (std * std)
    return wp.exp(-total / float(nj))


@wp.func
def body_ang_vel(env: LeggedEnv, w: int) -> float:
    """The roll and pitch rates of the robot's angvel body, squared."""
    omega = angular_velocity(env.d, w, env.r.angvel_body)
    return omega[0] * omega[0] + omega[1] * omega[1]


@wp.func
def angular_momentum(env: LeggedEnv, w: int) -> float:
    """The whole body's angular momentum about its centre of mass, squared."""
    h = sensor3(env.d, w, env.r.angmom)
    return wp.dot(h, h)


@wp.func
def dof_pos_limits(env: LeggedEnv, w: int) -> float:
    """How far the joints are beyond their soft limits, summed."""
    r = env.r
    total = float(0.0)
    for j in range(r.joint_qpos.shape[0]):
        q = env.d.qpos[w, r.joint_qpos[j]]
        total += -wp.min(q - r.soft_lo[j], 0.0) + wp.max(q - r.soft_hi[j], 0.0)
    return total


@wp.func
def action_rate_l2(env: LeggedEnv, w: int) -> float:
    """|action - previous action|^2."""
    st = env.st
    total = float(0.0)
    for a in range(st.action.shape[1]):
        e = st.action[w, a] - st.prev_action[w, a]
        total += e * e
    return total


@wp.func
def air_time(env: LeggedEnv, w: int, p: AirTime) -> float:
    """Feet whose air time lies between the thresholds, counted while moving."""
    total = float(0.0)
    for f in range(env.r.foot_site.shape[0]):
        t = env.st.air_time[w, f]
        if t > p.threshold_min and t < p.threshold_max:
            total += 1.0
    return total * moving(env, w, p.command_threshold)


@wp.func
def foot_clearance(env: LeggedEnv, w: int, p: FootHeight) -> float:
    """|foot height - target| x the foot's planar speed, summed over the feet, while moving."""
    total = float(0.0)
    for f in range(env.r.foot_site.shape[0]):
        v = foot_velocity(env, w, f)
        total += wp.abs(env.st.foot_height[w, f] - p.target_height) * wp.sqrt(v[0] * v[0] + v[1] * v[1])
    return total * moving(env, w, p.command_threshold)


@wp.func
def foot_swing_height(env: LeggedEnv, w: int, p: FootHeight) -> float:
    """(peak height of the swing / target - 1)^2 for each foot landing this step, while moving. Keeps each foot's
    peak in ``env.st.peak_height`` (not reset with an episode, as mjlab's)."""
    st = env.st
    total = float(0.0)
    for f in range(env.r.foot_site.shape[0]):
        if not in_contact(env, w, f):
            st.peak_height[w, f] = wp.max(st.peak_height[w, f], st.foot_height[w, f])
        if first_contact(env, w, f):
            e = st.peak_height[w, f] / p.target_height - 1.0
            total += e * e
            st.peak_height[w, f] = 0.0
    return total * moving(env, w, p.command_threshold)


@wp.func
def foot_slip(env: LeggedEnv, w: int, p: Moving) -> float:
    """The planar speed of each foot on the ground, squared, summed, while moving."""
    total = float(0.0)
    for f in range(env.r.foot_site.shape[0]):
        if in_contact(env, w, f):
            v = foot_velocity(env, w, f)
            total += v[0] * v[0] + v[1] * v[1]
    return total * moving(env, w, p.command_threshold)


@wp.func
def soft_landing(env: LeggedEnv, w: int, p: Moving) -> float:
    """The contact force of each foot landing this step, summed, while moving."""
    total = float(0.0)
    for f in range(env.r.foot_site.shape[0]):
        if first_contact(env, w, f):
            total += wp.length(sensor3(env.d, w, env.r.foot_force[f]))
    return total * moving(env, w, p.command_threshold)


@wp.func
def contact_steps(env: LeggedEnv, w: int, p: ContactGroup) -> float:
    """Physics steps of this control step in which a contact of the group felt more than the threshold."""
    return float(env.st.collision_hits[w, p.group])
