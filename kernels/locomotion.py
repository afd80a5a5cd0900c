"""One control step of the locomotion tasks after the physics: observations, rewards,
terminations and truncations, and per-env episode accumulators."""

import warp as wp

from kernels.observations import potential, root_position, write_observation
from kernels.params import LocomotionParams
from kernels.rewards import locomotion_reward

# Nothing differentiates through these kernels; skipping adjoint code shortens their compile.
wp.set_module_options({"enable_backward": False})


@wp.kernel
def locomotion_step(
    p: LocomotionParams,
    joint_q: wp.array2d[float],  # (N, C)
    joint_qd: wp.array2d[float],  # (N, D)
    dof_lower: wp.array[float],  # (A,)
    dof_upper: wp.array[float],  # (A,)
    dof_force: wp.array2d[float],  # (N, A)
    contact_wrench: wp.array2d[float],  # (N*B, 6)
    foot_bodies: wp.array[wp.int32],  # (F,)
    bodies_per_env: int,
    actions: wp.array2d[float],  # (N, A) applied this step
    effort_ratio: wp.array[float],  # (A,)
    potentials: wp.array[float],  # (N,) in: last step's, out: this step's
    ep_length: wp.array[wp.int32],  # (N,) steps so far in the episode
    ep_return: wp.array[float],  # (N,)
    ep_forward: wp.array[float],  # (N,) sum of root forward (x) velocity over the episode
    obs: wp.array2d[float],  # (N, O) out
    reward: wp.array[float],  # (N,) out
    terminated: wp.array[wp.bool],  # (N,) out: fell, or the state is no longer finite
    truncated: wp.array[wp.bool],  # (N,) out: reached the episode length
    done: wp.array[wp.bool],  # (N,) out: terminated or truncated
    diverged: wp.array[wp.bool],  # (N,) out: the physics blew up (NaN/inf or beyond max_speed) in this env
):
    env = wp.tid()
    # A world is "diverged" when its state is NaN/inf or moves faster than any robot can: a solver
    # blow-up, whose enormous progress reward would wreck a value function if it were passed on.
    sane = bool(True)
    for i in range(joint_q.shape[1]):
        if not wp.isfinite(joint_q[env, i]):
            sane = False
    for i in range(joint_qd.shape[1]):
        v = joint_qd[env, i]
        if not wp.isfinite(v) or wp.abs(v) > p.max_speed:
            sane = False

    write_observation(env, p, joint_q, joint_qd, dof_lower, dof_upper, dof_force, contact_wrench,
                      foot_bodies, bodies_per_env, actions, 0, obs)

    new_potential = potential(p, root_position(joint_q, env))
    progress = new_potential - potentials[env]
    if wp.abs(progress) > p.max_speed:
        sane = False  # the root jumped farther in one step than max_speed allows
    r = locomotion_reward(env, p, obs, actions, effort_ratio, progress)
    potentials[env] = new_potential
    fell = obs[env, 0] < p.termination_height
    if fell:
        r = p.death_cost
    if not sane:
        # nothing about this step is meaningful: end the episode without reward or bootstrap
        r = 0.0
        fell = True

    length = ep_length[env] + 1
    ep_length[env] = length
    ep_return[env] = ep_return[env] + r
    if sane:
        ep_forward[env] = ep_forward[env] + joint_qd[env, 0]
    trunc = (length >= p.episode_length) and not fell

    reward[env] = r
    terminated[env] = fell
    truncated[env] = trunc
    done[env] = fell or trunc
    diverged[env] = not sane


@wp.kernel
def advance_rng(rng_state: wp.array[wp.int32]):  # (2,): seed, step counter
    rng_state[1] = rng_state[1] + 1
