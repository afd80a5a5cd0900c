"""Observation, reward, termination and episode bookkeeping of Gymnasium's MuJoCo tasks (v5), one
thread per world, after the physics of a step.

Gymnasium reads everything after ``mj_step`` and ``mj_rnePostConstraint``: qpos and qvel of the new
state, but body positions, com inertias and velocities, actuator and contact forces as the last
physics step's forward pass left them (one physics step behind the state). MuJoCo Warp's ``Data``
after ``step`` holds the same, so these kernels read it as it is. After a reset, Gymnasium's
observation comes from ``mj_resetData`` and ``mj_forward`` of the new state: kinematics of the new
state (the env runs MuJoCo Warp's kinematics pass before ``write_reset_observation``), and zero
actuator, constraint and contact forces.
"""

import warp as wp

from kernels.common import StepOutputs, state_is_finite
from kernels.suite.params import (
    CONTACT_CLIPPED_COST,
    CONTACT_CLIPPED_FORCES,
    DOUBLE_PENDULUM,
    FORWARD,
    PENDULUM,
    POSITION_BODY,
    POSITION_MASS_CENTER,
    POSITION_QPOS_X,
    PUSHER,
    REACHER,
    STANDUP,
    DoublePendulumTerm,
    ForwardTerm,
    GymEpisodes,
    GymParams,
    MjView,
    PendulumTerm,
    PusherTerm,
    ReacherTerm,
    StandupTerm,
    SuiteState,
)

wp.set_module_options({"enable_backward": False})


@wp.func
def clipf(x: float, lo: float, hi: float):
    return wp.min(wp.max(x, lo), hi)


@wp.func
def position(p: GymParams, d: MjView, w: int):
    """The (x, y) position whose change over a step is the task's forward speed."""
    if p.position_source == POSITION_QPOS_X:
        return wp.vec2(d.qpos[w, 0], 0.0)
    if p.position_source == POSITION_BODY:
        frame = d.xpos[w, p.main_body]
        return wp.vec2(frame[0], frame[1])
    if p.position_source == POSITION_MASS_CENTER:
        c = wp.vec3(0.0)
        for b in range(d.body_mass.shape[0]):
            c += d.body_mass[b] * d.xipos[w, b]
        c = c / d.total_mass
        return wp.vec2(c[0], c[1])
    return wp.vec2(d.qpos[w, 0], d.qpos[w, 1])


@wp.func
def write_observation(p: GymParams, d: MjView, w: int, after_reset: int, obs: wp.array2d[float]):
    """Gymnasium's ``_get_obs()``. ``after_reset``: actuator, constraint and contact forces read 0."""
    nq = d.qpos.shape[1]
    nv = d.qvel.shape[1]
    k = int(0)
    if p.kind == PENDULUM:
        for i in range(nq):
            obs[w, k] = d.qpos[w, i]
            k += 1
        for i in range(nv):
            obs[w, k] = d.qvel[w, i]
            k += 1
    elif p.kind == DOUBLE_PENDULUM:
        obs[w, 0] = d.qpos[w, 0]
        for i in range(1, nq):
            obs[w, i] = wp.sin(d.qpos[w, i])
            obs[w, i + nq - 1] = wp.cos(d.qpos[w, i])
        k = int(2 * nq - 1)
        for i in range(nv):
            obs[w, k] = clipf(d.qvel[w, i], -10.0, 10.0)
            k += 1
        force = float(0.0)
        if after_reset == 0:
            force = clipf(d.qfrc_constraint[w, 0], -10.0, 10.0)
        obs[w, k] = force
    elif p.kind == REACHER:
        for i in range(2):
            obs[w, i] = wp.cos(d.qpos[w, i])
            obs[w, 2 + i] = wp.sin(d.qpos[w, i])
        k = int(4)
        for i in range(2, nq):
            obs[w, k] = d.qpos[w, i]
            k += 1
        for i in range(2):
            obs[w, k] = d.qvel[w, i]
            k += 1
        gap = d.xpos[w, p.body_a] - d.xpos[w, p.body_b]
        obs[w, k] = gap[0]
        obs[w, k + 1] = gap[1]
    elif p.kind == PUSHER:
        for i in range(7):
            obs[w, i] = d.qpos[w, i]
            obs[w, 7 + i] = d.qvel[w, i]
        for j in range(3):
            obs[w, 14 + j] = d.xpos[w, p.body_a][j]
            obs[w, 17 + j] = d.xpos[w, p.body_b][j]
            obs[w, 20 + j] = d.xpos[w, p.body_c][j]
    else:  # FORWARD, STANDUP: qpos, qvel, then the com-based quantities each task asks for
        for i in range(p.qpos_skip, nq):
            obs[w, k] = d.qpos[w, i]
            k += 1
        for i in range(nv):
            obs[w, k] = clipf(d.qvel[w, i], -p.qvel_clip, p.qvel_clip)
            k += 1
        nb = d.xpos.shape[1]
        if p.obs_cinert != 0:
            for b in range(1, nb):
                for j in range(10):
                    obs[w, k] = d.cinert[w, b][j]
                    k += 1
        if p.obs_cvel != 0:
            for b in range(1, nb):
                for j in range(6):
                    obs[w, k] = d.cvel[w, b][j]
                    k += 1
        if p.obs_qfrc_actuator != 0:
            for i in range(6, nv):
                force = float(0.0)
                if after_reset == 0:
                    force = d.qfrc_actuator[w, i]
                obs[w, k] = force
                k += 1
        if p.obs_cfrc_ext != 0:
            for b in range(1, nb):
                for j in range(6):
                    force = float(0.0)
                    if after_reset == 0:
                        force = clipf(d.cfrc_ext[w, b][j], p.cfrc_lo, p.cfrc_hi)
                    obs[w, k] = force
                    k += 1


@wp.func
def contact_cost(p: GymParams, d: MjView, w: int):
    total = float(0.0)
    for b in range(d.cfrc_ext.shape[1]):
        f = d.cfrc_ext[w, b]
        for j in range(6):
            x = f[j]
            if p.contact_cost_mode == CONTACT_CLIPPED_FORCES:
                x = clipf(x, p.cfrc_lo, p.cfrc_hi)
            total += x * x
    if p.contact_cost_mode == CONTACT_CLIPPED_COST:
        return clipf(p.contact_cost_weight * total, p.contact_lo, p.contact_hi)
    if p.contact_cost_mode == CONTACT_CLIPPED_FORCES:
        return p.contact_cost_weight * total
    return 0.0


@wp.func
def state_entry(d: MjView, w: int, i: int):
    """Entry ``i`` of Gymnasium's ``state_vector()``: qpos, then qvel."""
    nq = d.qpos.shape[1]
    if i < nq:
        return d.qpos[w, i]
    return d.qvel[w, i - nq]


@wp.func
def is_healthy(p: GymParams, d: MjView, w: int):
    nq = d.qpos.shape[1]
    nv = d.qvel.shape[1]
    healthy = True
    if p.healthy_z_index >= 0:
        z = d.qpos[w, p.healthy_z_index]
        if p.healthy_z_inclusive != 0:
            healthy = healthy and p.healthy_z_lo <= z and z <= p.healthy_z_hi
        else:
            healthy = healthy and p.healthy_z_lo < z and z < p.healthy_z_hi
    if p.healthy_angle_index >= 0:
        a = d.qpos[w, p.healthy_angle_index]
        healthy = healthy and p.healthy_angle_lo < a and a < p.healthy_angle_hi
    if p.healthy_state_lo > -1.0e30 or p.healthy_state_hi < 1.0e30:  # Hopper: state_vector()[2:] in range
        for i in range(2, nq + nv):
            s = state_entry(d, w, i)
            if not (p.healthy_state_lo < s and s < p.healthy_state_hi):
                healthy = False
    if p.healthy_finite != 0:  # Ant: the whole state finite
        for i in range(nq + nv):
            if not wp.isfinite(state_entry(d, w, i)):
                healthy = False
    return healthy


@wp.func
def sum_squares(a: wp.array2d[float], w: int):
    total = float(0.0)
    for i in range(a.shape[1]):
        total += a[w, i] * a[w, i]
    return total


def step_kernel(rewards, Rewards, terminations, Terminations):
    """The step's kernel of a task whose own terms (beside Gymnasium's) are the generated ``rewards`` and
    ``terminations`` (``warpgym.tasks.dispatch``) with their parameter structs; made once per pair of tables, so
    every task without terms of its own shares one."""
    key = rewards, terminations
    if key in _KERNELS:
        return _KERNELS[key]

    @wp.kernel(enable_backward=False, module="unique")
    def gym_step(env: SuiteState, reward_params: Rewards, weights: wp.array[float], termination_params: Terminations,
                 out: StepOutputs):
        """Observation, reward, reward terms (``ep.terms``, each at its column of the kind's ``TERMS``; the task's
        own in ``ep.extra``), termination and episode statistics after a step's physics."""
        w = wp.tid()
        p = env.p
        d = env.d
        ep = env.ep
        write_observation(p, d, w, 0, out.obs)
        ctrl_cost = p.ctrl_cost_weight * sum_squares(ep.actions, w)
        reward = float(0.0)
        terminated = False
        forward = float(0.0)
        if p.kind == FORWARD:
            after = position(p, d, w)
            velocity = (after - wp.vec2(ep.before[w, 0], ep.before[w, 1])) / p.dt
            ep.before[w, 0] = after[0]
            ep.before[w, 1] = after[1]
            healthy = is_healthy(p, d, w)
            survive = float(0.0)
            if healthy:
                survive = p.healthy_reward
            contact = contact_cost(p, d, w)
            forward = velocity[0]
            reward_forward = p.forward_reward_weight * velocity[0]
            reward = reward_forward + survive - ctrl_cost - contact
            terminated = (not healthy) and p.terminate_when_unhealthy != 0
            ep.terms[w, ForwardTerm.reward_forward] = reward_forward
            ep.terms[w, ForwardTerm.reward_ctrl] = -ctrl_cost
            ep.terms[w, ForwardTerm.reward_survive] = survive
            ep.terms[w, ForwardTerm.reward_contact] = -contact
            ep.terms[w, ForwardTerm.x_velocity] = velocity[0]
            ep.terms[w, ForwardTerm.y_velocity] = velocity[1]
            ep.terms[w, ForwardTerm.x_position] = d.qpos[w, 0]
        elif p.kind == STANDUP:
            linup = d.qpos[w, 2] / p.timestep  # Gymnasium divides by MuJoCo's timestep, not the env's dt
            impact = contact_cost(p, d, w)
            reward = linup - ctrl_cost - impact + 1.0
            ep.terms[w, StandupTerm.reward_linup] = linup
            ep.terms[w, StandupTerm.reward_quadctrl] = -ctrl_cost
            ep.terms[w, StandupTerm.reward_impact] = -impact
            ep.terms[w, StandupTerm.x_position] = d.qpos[w, 0]
            ep.terms[w, StandupTerm.y_position] = d.qpos[w, 1]
        elif p.kind == PENDULUM:
            terminated = not (wp.abs(d.qpos[w, 1]) <= 0.2)
            if terminated:
                reward = 0.0
            else:
                reward = 1.0
            ep.terms[w, PendulumTerm.reward_survive] = reward
        elif p.kind == DOUBLE_PENDULUM:
            tip = d.site_xpos[w, 0]
            terminated = tip[2] <= 1.0
            distance = 0.01 * tip[0] * tip[0] + (tip[2] - 2.0) * (tip[2] - 2.0)
            v1 = d.qvel[w, 1]
            v2 = d.qvel[w, 2]
            velocity_penalty = 0.001 * v1 * v1 + 0.005 * v2 * v2
            alive = float(0.0)
            if not terminated:
                alive = p.healthy_reward
            reward = alive - distance - velocity_penalty
            ep.terms[w, DoublePendulumTerm.reward_survive] = alive
            ep.terms[w, DoublePendulumTerm.distance_penalty] = -distance
            ep.terms[w, DoublePendulumTerm.velocity_penalty] = -velocity_penalty
        elif p.kind == REACHER:
            dist = -wp.length(d.xpos[w, p.body_a] - d.xpos[w, p.body_b]) * p.dist_weight
            reward = dist - ctrl_cost
            ep.terms[w, ReacherTerm.reward_dist] = dist
            ep.terms[w, ReacherTerm.reward_ctrl] = -ctrl_cost
        elif p.kind == PUSHER:
            near = -wp.length(d.xpos[w, p.body_b] - d.xpos[w, p.body_a]) * p.near_weight
            dist = -wp.length(d.xpos[w, p.body_b] - d.xpos[w, p.body_c]) * p.dist_weight
            reward = dist - ctrl_cost + near
            ep.terms[w, PusherTerm.reward_dist] = dist
            ep.terms[w, PusherTerm.reward_ctrl] = -ctrl_cost
            ep.terms[w, PusherTerm.reward_near] = near

        # the task's own terms, after Gymnasium's: a weight times the value a step, as Gymnasium weighs its terms
        # (mjlab's tasks also multiply by dt)
        reward += rewards(env, w, reward_params, weights, 1.0, ep.extra)
        ended = terminations(env, w, termination_params)
        terminated = terminated or ended[0] != 0

        # A state that is no longer finite ends the episode with reward 0 (Gymnasium would go on
        # returning NaN); info["diverged"] flags it and the observation it ended on reads 0.
        diverged = not state_is_finite(d.qpos, d.qvel, w)
        if diverged:
            reward = 0.0
            terminated = True
            forward = 0.0
            for k in range(weights.shape[0]):
                ep.extra[w, k] = 0.0
            for i in range(out.obs.shape[1]):
                out.obs[w, i] = 0.0
        out.diverged[w] = diverged

        length = ep.length[w] + 1
        ep.length[w] = length
        ep.total_return[w] = ep.total_return[w] + reward
        ep.travel[w] = ep.travel[w] + forward * p.dt
        ep.speed[w] = ep.travel[w] / (float(length) * p.dt)
        truncated = length >= p.episode_length or ended[1] != 0
        out.reward[w] = reward
        out.terminated[w] = terminated
        out.truncated[w] = truncated
        out.time_outs[w] = truncated and not terminated
        done = terminated or truncated
        out.done[w] = done
        if done:
            for i in range(out.obs.shape[1]):
                out.final_obs[w, i] = out.obs[w, i]
            ep.ended_return[w] = ep.total_return[w]
            ep.ended_length[w] = length
            ep.ended_speed[w] = ep.speed[w]

    _KERNELS[key] = gym_step
    return gym_step


_KERNELS: dict = {}


@wp.kernel
def write_reset_observation(p: GymParams, force_all: int, d: MjView, ep: GymEpisodes, out: StepOutputs):
    """The first observation of the worlds reset this step (all with ``force_all``), and the position
    their first step's forward speed is measured from, from the kinematics of the new state."""
    w = wp.tid()
    if force_all == 0 and not out.done[w]:
        return
    write_observation(p, d, w, 1, out.obs)
    start = position(p, d, w)
    ep.before[w, 0] = start[0]
    ep.before[w, 1] = start[1]


@wp.kernel
def apply_gym_actions(
    actions_in: wp.array2d[float],  # (N, U) as the learner gave them
    unit: int,  # 1: actions in [-1, 1] (clipped), mapped linearly onto [low, high]; 0: as given
    low: wp.array[float],  # (U,) the actuators' control range
    high: wp.array[float],
    ctrl: wp.array2d[float],  # (N, U) out: MuJoCo's controls, which MuJoCo clamps to ctrlrange itself
    actions: wp.array2d[float],  # (N, U) out: what the control cost is charged on
    nan_count: wp.array[wp.int32],  # (N,) out: non-finite entries, applied as 0
):
    w = wp.tid()
    bad = int(0)
    for i in range(actions_in.shape[1]):
        a = actions_in[w, i]
        if not wp.isfinite(a):
            a = 0.0
            bad += 1
        if unit != 0:
            a = low[i] + (clipf(a, -1.0, 1.0) + 1.0) * 0.5 * (high[i] - low[i])
        ctrl[w, i] = a
        actions[w, i] = a
    nan_count[w] = bad
