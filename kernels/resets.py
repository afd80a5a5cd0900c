"""Masked reset of the locomotion envs that finished, inside the same step (same-step autoreset)."""

import warp as wp

from kernels.observations import potential, write_observation
from kernels.params import LocomotionParams
from kernels.tensor_api import ROOT_COORDS, ROOT_DOFS

# Nothing differentiates through these kernels; skipping adjoint code shortens their compile.
wp.set_module_options({"enable_backward": False})


@wp.func
def env_rng(rng_state: wp.array[wp.int32], env: int):
    # fresh noise per (seed, step, env) from device counters, so a replayed graph draws new numbers
    step_rng = wp.rand_init(rng_state[0], rng_state[1])
    return wp.rand_init(wp.randi(step_rng), env)


@wp.kernel
def reset_finished_envs(
    p: LocomotionParams,
    force_all: int,  # 1: reset every env and record nothing (an explicit reset())
    rng_state: wp.array[wp.int32],  # (2,)
    default_dof_pos: wp.array[float],  # (A,)
    dof_lower: wp.array[float],  # (A,)
    dof_upper: wp.array[float],  # (A,)
    dof_force: wp.array2d[float],  # (N, A)
    contact_wrench: wp.array2d[float],  # (N*B, 6)
    foot_bodies: wp.array[wp.int32],  # (F,)
    bodies_per_env: int,
    actions: wp.array2d[float],  # (N, A)
    terminated: wp.array[wp.bool],  # (N,)
    truncated: wp.array[wp.bool],  # (N,)
    done: wp.array[wp.bool],  # (N,)
    joint_q: wp.array2d[float],  # (N, C) out
    joint_qd: wp.array2d[float],  # (N, D) out
    qacc_warmstart: wp.array2d[float],  # (N, nv) out: the solver's warm start, stale after a reset
    potentials: wp.array[float],  # (N,) out
    ep_length: wp.array[wp.int32],  # (N,) out
    ep_return: wp.array[float],  # (N,) out
    ep_forward: wp.array[float],  # (N,) out
    stat_return: wp.array[float],  # (N,) out: return of the episode that just ended
    stat_length: wp.array[wp.int32],  # (N,) out
    stat_speed: wp.array[float],  # (N,) out: its mean forward speed [m/s]
    final_obs: wp.array2d[float],  # (N, O) out: the observation the episode ended on
    obs: wp.array2d[float],  # (N, O) in/out: replaced by the first observation of the new episode
):
    env = wp.tid()
    if force_all != 0:
        terminated[env] = False
        truncated[env] = False
        done[env] = False
    elif not done[env]:
        return
    else:
        for i in range(obs.shape[1]):
            final_obs[env, i] = obs[env, i]
        length = ep_length[env]
        stat_return[env] = ep_return[env]
        stat_length[env] = length
        stat_speed[env] = ep_forward[env] / float(wp.max(length, 1))
    ep_length[env] = 0
    ep_return[env] = 0.0
    ep_forward[env] = 0.0

    rng = env_rng(rng_state, env)
    for i in range(3):
        joint_q[env, i] = p.start_pos[i]
    for i in range(4):
        joint_q[env, 3 + i] = p.start_rot[i]
    for i in range(ROOT_DOFS):
        joint_qd[env, i] = 0.0
    for j in range(default_dof_pos.shape[0]):
        q = default_dof_pos[j] + wp.randf(rng, -p.dof_pos_noise, p.dof_pos_noise)
        joint_q[env, ROOT_COORDS + j] = wp.clamp(q, dof_lower[j], dof_upper[j])
        joint_qd[env, ROOT_DOFS + j] = wp.randf(rng, -p.dof_vel_noise, p.dof_vel_noise)
    for j in range(qacc_warmstart.shape[1]):
        qacc_warmstart[env, j] = 0.0

    potentials[env] = potential(p, p.start_pos)
    write_observation(env, p, joint_q, joint_qd, dof_lower, dof_upper, dof_force, contact_wrench,
                      foot_bodies, bodies_per_env, actions, 1, obs)
