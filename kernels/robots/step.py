"""One control step of the locomotion tasks after the physics: observations, rewards,
terminations and truncations, and per-env episode accumulators."""

import warp as wp

from kernels.common import StepOutputs
from kernels.robots.buffers import EpisodeBuffers, RobotState, RobotView
from kernels.robots.observations import forward_speed, potential, root_position, write_observation
from kernels.robots.params import LocomotionParams
from kernels.robots.rewards import locomotion_reward

# Nothing differentiates through these kernels; skipping adjoint code shortens their compile.
wp.set_module_options({"enable_backward": False})


@wp.func
def is_sane(p: LocomotionParams, robot: RobotView, env: int):
    # A world is "diverged" when its state is NaN/inf or moves faster than any robot can: a solver
    # blow-up, whose enormous progress reward would wreck a value function if it were passed on.
    sane = bool(True)
    for i in range(robot.joint_q.shape[1]):
        if not wp.isfinite(robot.joint_q[env, i]):
            sane = False
    for i in range(robot.joint_qd.shape[1]):
        v = robot.joint_qd[env, i]
        if not wp.isfinite(v) or wp.abs(v) > p.max_speed:
            sane = False
    return sane


@wp.func
def record_ended_episode(env: int, episodes: EpisodeBuffers, out: StepOutputs):
    # recorded by the step that ends the episode, as in the suite's step: the reset that follows only resets
    for i in range(out.obs.shape[1]):
        out.final_obs[env, i] = out.obs[env, i]
    episodes.ended_return[env] = episodes.total_return[env]
    episodes.ended_length[env] = episodes.length[env]
    episodes.ended_speed[env] = episodes.speed[env]


def step_kernel(rewards, Rewards, terminations, Terminations):
    """The step's kernel of a task whose own terms (beside Isaac Gym's reward) are the generated ``rewards`` and
    ``terminations`` (``warpgym.tasks.dispatch``) with their parameter structs; made once per pair of tables, so the
    tasks without terms of their own share one."""
    key = rewards, terminations
    if key in _KERNELS:
        return _KERNELS[key]

    @wp.kernel(enable_backward=False, module="unique")
    def locomotion_step(state: RobotState, reward_params: Rewards, weights: wp.array[float],
                        termination_params: Terminations, out: StepOutputs):
        env = wp.tid()
        p = state.p
        robot = state.r
        episodes = state.ep
        sane = is_sane(p, robot, env)
        write_observation(env, p, robot, 0, out.obs)

        pos = root_position(robot.joint_q, env)
        new_potential = potential(p, pos)
        progress = new_potential - episodes.potential[env]
        if wp.abs(progress) > p.max_speed:
            sane = False  # the root jumped farther in one step than max_speed allows
        r = locomotion_reward(env, p, out.obs, robot.actions, robot.effort_ratio, progress)
        # the task's own terms, after Isaac Gym's reward: a weight times the value a step, as its terms are weighed
        r += rewards(state, env, reward_params, weights, 1.0, episodes.extra)
        episodes.potential[env] = new_potential
        fell = out.obs[env, 0] < p.termination_height
        ended = terminations(state, env, termination_params)
        if fell or not sane:  # the death cost, or nothing, in place of every term
            for k in range(weights.shape[0]):
                episodes.extra[env, k] = 0.0
        if fell:
            r = p.death_cost
        fell = fell or ended[0] != 0
        if not sane:
            # nothing about this step is meaningful: end the episode without reward or bootstrap
            r = 0.0
            fell = True

        length = episodes.length[env] + 1
        episodes.length[env] = length
        episodes.total_return[env] = episodes.total_return[env] + r
        if sane:  # a blown-up state travelled nowhere: the speed keeps its last sane value
            episodes.speed[env] = forward_speed(p, pos, length)
        # Gymnasium's TimeLimit: the time limit truncates whether or not the step also terminated (a learner
        # bootstraps only a truncation without a termination); the suite's step does the same
        trunc = length >= p.episode_length or ended[1] != 0

        out.reward[env] = r
        out.terminated[env] = fell
        out.truncated[env] = trunc
        out.time_outs[env] = trunc and not fell
        out.done[env] = fell or trunc
        out.diverged[env] = not sane
        if fell or trunc:
            record_ended_episode(env, episodes, out)

    _KERNELS[key] = locomotion_step
    return locomotion_step


_KERNELS: dict = {}
