"""After a control step's physics (mjlab's ManagerBasedRlEnv.step, between the physics and the resets): the
step counters, terminations, every reward term, the ended episodes' statistics and last observations, and the
interval events that fall due (pushes); and the observation pass after the resets. Both kernels are made per task
from its tables of terms (``step_kernels``), the terms called in the tables' order.

mjlab reads all of it from MuJoCo's data as the last physics step left it: positions and velocities are the new
state's, but body frames, com velocities, site positions and sensor data are those the last physics step's
forward pass computed (one physics step behind), and the feet's heights those of the last observation. These
kernels read the same. Each term's value is ``weight * dt * kernel`` (mjlab's reward manager scales by the
control step); a term of weight 0 is skipped, as mjlab skips it; a value that is not finite counts as 0.
"""

import warp as wp

from kernels.common import Intervals, ObsLayout, StepOutputs, state_is_finite, stream
from kernels.legged.observations import foot_height_now
from kernels.legged.params import LeggedEnv, LeggedEpisodes, LeggedState
from kernels.legged.random import FINAL_OBSERVATION, INTERVAL, OBSERVATION

wp.set_module_options({"enable_backward": False})


@wp.kernel
def count_step(st: LeggedState):
    st.step_count[0] = st.step_count[0] + 1


def step_kernels(rewards, Rewards, terminations, Terminations, policy, Policy, critic, Critic, events, Events):
    """The step's and the observation's kernels of one task's tables (``warpgym.tasks.dispatch``: the generated
    functions and their parameter structs; ``events``: its interval events'), made once per table."""
    key = rewards, terminations, policy, critic, events
    if key in _KERNELS:
        return _KERNELS[key]

    @wp.kernel(enable_backward=False, module="unique")
    def legged_step(env: LeggedEnv, rng_state: wp.array[wp.int32], reward_params: Rewards, weights: wp.array[float],
                    termination_params: Terminations, policy_params: Policy, policy_layout: ObsLayout,
                    critic_params: Critic, critic_layout: ObsLayout, event_params: Events, timers: Intervals,
                    ep: LeggedEpisodes, out: StepOutputs, final_critic: wp.array2d[float]):
        w = wp.tid()
        p = env.p
        d = env.d
        length = ep.length[w] + 1
        ep.length[w] = length
        ended = terminations(env, w, termination_params)
        fell = ended[0] != 0
        time_out = length >= p.episode_length or ended[1] != 0
        reward = rewards(env, w, reward_params, weights, p.dt, ep.terms)
        # A state that is no longer finite ends the episode with reward 0 and is reset (mjlab would go on stepping
        # it); info["diverged"] flags it
        diverged = not state_is_finite(d.qpos, d.qvel, w)
        if diverged:
            reward = 0.0
            for k in range(weights.shape[0]):
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
            rng = stream(rng_state, w, FINAL_OBSERVATION)
            rng = policy(env, w, rng, 0, policy_params, policy_layout, out.final_obs)
            critic(env, w, rng, 0, critic_params, critic_layout, final_critic)
            ep.ended_return[w] = ep.total_return[w]
            ep.ended_length[w] = length
            ep.ended_errors[w, 0] = ep.errors[w, 0]
            ep.ended_errors[w, 1] = ep.errors[w, 1]

        # after the terms, which read the velocities the physics left (mjlab's interval events follow its rewards)
        live = int(1)
        if diverged:
            live = 0
        events(env, w, stream(rng_state, w, INTERVAL), live, event_params, timers, p.dt)

    @wp.kernel(enable_backward=False, module="unique")
    def observe(env: LeggedEnv, rng_state: wp.array[wp.int32], policy_params: Policy, policy_layout: ObsLayout,
                critic_params: Critic, critic_layout: ObsLayout, actor: wp.array2d[float],
                critic_out: wp.array2d[float]):
        """mjlab's observation pass after the step's forward pass (and, on rough ground, the scans): the feet's
        heights, kept for the next step's rewards, and both observations."""
        w = wp.tid()
        for f in range(env.r.foot_site.shape[0]):
            env.st.foot_height[w, f] = foot_height_now(env, w, f)
        fresh = env.st.fresh[w]  # the first observation since the world's reset: a term's history starts from it
        rng = policy(env, w, stream(rng_state, w, OBSERVATION), fresh, policy_params, policy_layout, actor)
        critic(env, w, rng, fresh, critic_params, critic_layout, critic_out)
        env.st.fresh[w] = 0

    _KERNELS[key] = legged_step, observe
    return legged_step, observe


_KERNELS: dict = {}
