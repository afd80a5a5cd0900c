"""Gymnasium's ``reset_model()`` of the MuJoCo tasks for the worlds that finished (same-step autoreset).

The drawn state goes into MuJoCo Warp's qpos and qvel; the env then runs MuJoCo Warp's kinematics
where the first observation needs it and ``kernels.suite.step.write_reset_observation``. Gymnasium's
``mj_resetData`` also zeroes the solver's warm start and the controls: so does this.
"""

import warp as wp

from kernels.common import StepOutputs, env_rng, resets_world
from kernels.suite.params import GOAL_PUSHER, GOAL_REACHER, GymEpisodes, GymParams, MjView

wp.set_module_options({"enable_backward": False})


@wp.func
def draw_goal(p: GymParams, d: MjView, w: int, rng: wp.uint32):
    nq = d.qpos.shape[1]
    nv = d.qvel.shape[1]
    if p.goal_mode == GOAL_REACHER:  # the target uniform in the disc of radius 0.2, at rest
        goal = wp.vec2(wp.randf(rng, -0.2, 0.2), wp.randf(rng, -0.2, 0.2))
        while wp.length(goal) >= 0.2:
            goal = wp.vec2(wp.randf(rng, -0.2, 0.2), wp.randf(rng, -0.2, 0.2))
        d.qpos[w, nq - 2] = goal[0]
        d.qpos[w, nq - 1] = goal[1]
        d.qvel[w, nv - 2] = 0.0
        d.qvel[w, nv - 1] = 0.0
    elif p.goal_mode == GOAL_PUSHER:  # the cylinder more than 0.17 from the goal, which sits at the origin
        cylinder = wp.vec2(wp.randf(rng, -0.3, 0.0), wp.randf(rng, -0.2, 0.2))
        while wp.length(cylinder) <= 0.17:
            cylinder = wp.vec2(wp.randf(rng, -0.3, 0.0), wp.randf(rng, -0.2, 0.2))
        d.qpos[w, nq - 4] = cylinder[0]
        d.qpos[w, nq - 3] = cylinder[1]
        d.qpos[w, nq - 2] = 0.0
        d.qpos[w, nq - 1] = 0.0
        for i in range(nv - 4, nv):
            d.qvel[w, i] = 0.0


@wp.kernel
def reset_gym_worlds(p: GymParams, force_all: int, rng_state: wp.array[wp.int32], d: MjView, ep: GymEpisodes,
                     out: StepOutputs):
    w = wp.tid()
    if not resets_world(force_all, out, w):
        return
    rng = env_rng(rng_state, w)
    for i in range(d.qpos.shape[1]):
        d.qpos[w, i] = d.qpos0[i] + wp.randf(rng, -p.qpos_noise, p.qpos_noise)
    for i in range(d.qvel.shape[1]):
        if p.qvel_noise_normal != 0:
            d.qvel[w, i] = p.qvel_noise * wp.randn(rng)
        else:
            d.qvel[w, i] = wp.randf(rng, -p.qvel_noise, p.qvel_noise)
        d.warm_start[w, i] = 0.0
    draw_goal(p, d, w, rng)
    for i in range(d.ctrl.shape[1]):
        d.ctrl[w, i] = 0.0
    ep.length[w] = 0
    ep.total_return[w] = 0.0
    ep.travel[w] = 0.0
    ep.speed[w] = 0.0
