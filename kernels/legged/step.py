"""After a control step's physics (mjlab's ManagerBasedRlEnv.step, between the physics and the resets): the
step counters, terminations, every reward term, the ended episodes' statistics and last observations, and the
pushes that fall due.

mjlab reads all of it from MuJoCo's data as the last physics step left it: positions and velocities are the new
state's, but body frames, com velocities, site positions and sensor data are those the last physics step's
forward pass computed (one physics step behind), and the feet's heights those of the last observation. These
kernels read the same. Each term's value is ``weight * dt * kernel`` (mjlab's reward manager scales by the
control step); a term of weight 0 is skipped, as mjlab skips it; a value that is not finite counts as 0.
"""

import warp as wp

from kernels.common import StepOutputs, state_is_finite, stream
from kernels.legged.frames import angular_velocity, point_velocity, projected_gravity, rotate_inverse, root_velocity_b, sensor3
from kernels.legged.observations import write_observation
from kernels.legged.params import (ILLEGAL_CONTACT, SELF_COLLISION, SHANK_GROUND, TRUNK_GROUND, LeggedEpisodes,
                                   LeggedParams, LeggedRobot, LeggedState, MjLegged, Term)
from kernels.legged.random import FINAL_OBSERVATION, PUSH
from kernels.legged.terrain_levels import TerrainLevels, out_of_bounds

wp.set_module_options({"enable_backward": False})


@wp.kernel
def count_step(st: LeggedState):
    st.step_count[0] = st.step_count[0] + 1


@wp.func
def active(p: LeggedParams, st: LeggedState, w: int, threshold: float):
    """1 while the command's speed (|v_xy| + |yaw rate|) exceeds ``threshold``, else 0."""
    speed = wp.sqrt(st.command[w, 0] * st.command[w, 0] + st.command[w, 1] * st.command[w, 1]) + wp.abs(st.command[w, 2])
    if speed > threshold:
        return 1.0
    return 0.0


@wp.func
def posture(p: LeggedParams, r: LeggedRobot, d: MjLegged, st: LeggedState, w: int):
    speed = wp.sqrt(st.command[w, 0] * st.command[w, 0] + st.command[w, 1] * st.command[w, 1]) + wp.abs(st.command[w, 2])
    total = float(0.0)
    nj = r.joint_qpos.shape[0]
    for j in range(nj):
        std = r.std_running[j]
        if speed < p.walking_threshold:
            std = r.std_standing[j]
        elif speed < p.running_threshold:
            std = r.std_walking[j]
        e = d.qpos[w, r.joint_qpos[j]] - r.default_joint_pos[j]
        total += e * e / (std * std)
    return wp.exp(-total / float(nj))


@wp.func
def first_contact(p: LeggedParams, st: LeggedState, w: int, f: int):
    """A foot that landed within this control step (mjlab's compute_first_contact)."""
    t = st.contact_time[w, f]
    return t > 0.0 and t < p.dt + 1.0e-6


@wp.func
def feet_terms(p: LeggedParams, r: LeggedRobot, d: MjLegged, st: LeggedState, w: int, term: int):
    """The per-foot terms, summed over the feet: air time, clearance, swing height (which updates the peaks), slip
    and landing force."""
    total = float(0.0)
    for f in range(r.foot_site.shape[0]):
        contact = d.sensordata[w, r.foot_found[f]] > 0.0
        h = st.foot_height[w, f]
        v = wp.vec3(0.0)
        if term == Term.foot_clearance or term == Term.foot_slip:
            v = point_velocity(d, w, r.foot_body[f], r.root_body, d.site_xpos[w, r.foot_site[f]])
        if term == Term.air_time:
            t = st.air_time[w, f]
            if t > p.air_min and t < p.air_max:
                total += 1.0
        elif term == Term.foot_clearance:
            total += wp.abs(h - p.clearance_height) * wp.sqrt(v[0] * v[0] + v[1] * v[1])
        elif term == Term.foot_swing_height:
            if not contact:
                st.peak_height[w, f] = wp.max(st.peak_height[w, f], h)
            if first_contact(p, st, w, f):
                e = st.peak_height[w, f] / p.swing_height - 1.0
                total += e * e
                st.peak_height[w, f] = 0.0
        elif term == Term.foot_slip:
            if contact:
                total += v[0] * v[0] + v[1] * v[1]
        elif term == Term.soft_landing:
            if first_contact(p, st, w, f):
                total += wp.length(sensor3(d, w, r.foot_force[f]))
    return total


@wp.func
def term_value(p: LeggedParams, r: LeggedRobot, d: MjLegged, st: LeggedState, w: int, term: int):
    """The unweighted kernel of one reward term."""
    if term == Term.track_linear_velocity:
        v, omega = root_velocity_b(d, r, w)
        ex = st.command[w, 0] - v[0]
        ey = st.command[w, 1] - v[1]
        return wp.exp(-(ex * ex + ey * ey + v[2] * v[2]) / p.lin_var)
    if term == Term.track_angular_velocity:
        v, omega = root_velocity_b(d, r, w)
        ez = st.command[w, 2] - omega[2]
        return wp.exp(-(ez * ez + omega[0] * omega[0] + omega[1] * omega[1]) / p.ang_var)
    if term == Term.upright:
        g = projected_gravity(d.xquat[w, r.upright_body])
        if p.upright_terrain != 0:  # the ground's normal in the body's frame: (0, 0, 1) when level with it
            g = rotate_inverse(d.xquat[w, r.upright_body], st.terrain_normal[w])
        return wp.exp(-(g[0] * g[0] + g[1] * g[1]) / p.upright_var)
    if term == Term.pose:
        return posture(p, r, d, st, w)
    if term == Term.body_ang_vel:
        omega = angular_velocity(d, w, r.angvel_body)
        return omega[0] * omega[0] + omega[1] * omega[1]
    if term == Term.angular_momentum:
        h = sensor3(d, w, r.angmom)
        return wp.dot(h, h)
    if term == Term.dof_pos_limits:
        total = float(0.0)
        for j in range(r.joint_qpos.shape[0]):
            q = d.qpos[w, r.joint_qpos[j]]
            total += -wp.min(q - r.soft_lo[j], 0.0) + wp.max(q - r.soft_hi[j], 0.0)
        return total
    if term == Term.action_rate_l2:
        total = float(0.0)
        for a in range(st.action.shape[1]):
            e = st.action[w, a] - st.prev_action[w, a]
            total += e * e
        return total
    if term == Term.air_time:
        return feet_terms(p, r, d, st, w, term) * active(p, st, w, p.air_command)
    if term == Term.foot_clearance:
        return feet_terms(p, r, d, st, w, term) * active(p, st, w, p.clearance_command)
    if term == Term.foot_swing_height:
        return feet_terms(p, r, d, st, w, term) * active(p, st, w, p.swing_command)
    if term == Term.foot_slip:
        return feet_terms(p, r, d, st, w, term) * active(p, st, w, p.slip_command)
    if term == Term.soft_landing:
        return feet_terms(p, r, d, st, w, term) * active(p, st, w, p.landing_command)
    if term == Term.shank_collision:
        return float(st.collision_hits[w, SHANK_GROUND])
    if term == Term.trunk_head_collision:
        return float(st.collision_hits[w, TRUNK_GROUND])
    return float(st.collision_hits[w, SELF_COLLISION])  # self_collisions


@wp.func
def push(p: LeggedParams, r: LeggedRobot, d: MjLegged, w: int, rng: wp.uint32):
    """mjlab's push_by_setting_velocity: the base's world velocity (from the last forward pass) plus a uniform
    draw, written into the free joint's qvel (linear in the world frame, angular in the base's, through the
    orientation in qpos). Draws from a copy of the caller's random state."""
    root = r.root_body
    lin = point_velocity(d, w, root, root, d.xpos[w, root])
    ang = angular_velocity(d, w, root)
    for i in range(3):
        lin[i] = lin[i] + wp.randf(rng, p.push_lo[i], p.push_hi[i])
    for i in range(3):
        ang[i] = ang[i] + wp.randf(rng, p.push_lo[3 + i], p.push_hi[3 + i])
    a = r.root_qpos + 3
    q = wp.quat(d.qpos[w, a], d.qpos[w, a + 1], d.qpos[w, a + 2], d.qpos[w, a + 3])
    ang_b = rotate_inverse(q, ang)
    for i in range(3):
        d.qvel[w, r.root_dof + i] = lin[i]
        d.qvel[w, r.root_dof + 3 + i] = ang_b[i]


@wp.kernel
def legged_step(p: LeggedParams, r: LeggedRobot, rng_state: wp.array[wp.int32], d: MjLegged, st: LeggedState,
                ep: LeggedEpisodes, t: TerrainLevels, out: StepOutputs, critic: wp.array2d[float],
                final_critic: wp.array2d[float]):
    w = wp.tid()
    length = ep.length[w] + 1
    ep.length[w] = length
    g = projected_gravity(d.xquat[w, r.root_body])
    fell = p.fall_over != 0 and wp.abs(wp.acos(wp.clamp(-g[2], -1.0, 1.0))) > p.limit_angle
    fell = fell or st.collision_hits[w, ILLEGAL_CONTACT] > 0
    # beyond the ground's edge ends an episode as a time-out (mjlab's out_of_terrain_bounds)
    time_out = length >= p.episode_length or out_of_bounds(t, r, d, w)

    reward = float(0.0)
    for k in range(p.weights.shape[0]):
        value = float(0.0)
        if p.weights[k] != 0.0:
            value = term_value(p, r, d, st, w, k) * p.weights[k] * p.dt
            if not wp.isfinite(value):
                value = 0.0
        ep.terms[w, k] = value
        reward += value

    # A state that is no longer finite ends the episode with reward 0 and is reset (mjlab would go on stepping
    # it); info["diverged"] flags it
    diverged = not state_is_finite(d.qpos, d.qvel, w)
    if diverged:
        reward = 0.0
        for k in range(p.weights.shape[0]):
            ep.terms[w, k] = 0.0
    terminated = fell or diverged
    ep.total_return[w] = ep.total_return[w] + reward
    out.reward[w] = reward
    out.terminated[w] = terminated
    out.truncated[w] = time_out
    out.time_outs[w] = time_out and not terminated
    out.diverged[w] = diverged
    done = terminated or time_out
    out.done[w] = done
    if done:
        write_observation(p, r, d, st, w, stream(rng_state, w, FINAL_OBSERVATION), out.final_obs, final_critic)
        ep.ended_return[w] = ep.total_return[w]
        ep.ended_length[w] = length
        ep.ended_errors[w, 0] = ep.errors[w, 0]
        ep.ended_errors[w, 1] = ep.errors[w, 1]

    # after the terms, which read the velocities the physics left (mjlab's interval events follow its rewards)
    st.push_time_left[w] = st.push_time_left[w] - p.dt
    if st.push_time_left[w] < 1.0e-6:
        rng = stream(rng_state, w, PUSH)
        st.push_time_left[w] = wp.randf(rng, p.push_interval_lo, p.push_interval_hi)
        if not diverged:
            push(p, r, d, w, rng)
