"""mjlab's reset of the worlds whose episode ended (the sensors' and managers' resets, then its reset events), and
its startup events, run once per world when the env is built. Both kernels are made per task from its table of
events (``reset_kernels``).

A reset world comes to rest, with zero controls and a fresh solver warm start (MuJoCo Warp's reset_data zeroes
them too); its action history, air and contact times and tracking errors restart; then the task's reset events
place it (the legged tasks': its default pose at its start on the ground, moved by a uniform offset in x, y, z and
yaw, its joints at their defaults plus mjlab's offset range, 0 in its config); it draws a new command and a new
time to each interval event's next run. The swing heights' peaks are not reset: mjlab's swing-height term keeps
them across episodes.
"""

import warp as wp

from kernels.common import Intervals, StepOutputs, restart_intervals, resets_world, stream
from kernels.legged.commands import draw_command
from kernels.legged.params import NUM_GROUPS, LeggedEnv, LeggedEpisodes
from kernels.legged.random import RESET, STARTUP

wp.set_module_options({"enable_backward": False})


def reset_kernels(events_reset, Reset, events_startup, Startup):
    """The reset's and the startup's kernels of one task's table of events (``warpgym.tasks.dispatch``: the
    generated functions of its reset and startup events and their parameter structs), made once per table."""
    key = events_reset, events_startup
    if key in _KERNELS:
        return _KERNELS[key]

    @wp.kernel(enable_backward=False, module="unique")
    def reset_legged_worlds(env: LeggedEnv, force_all: int, stagger: int, rng_state: wp.array[wp.int32],
                            reset_params: Reset, timers: Intervals, ep: LeggedEpisodes, out: StepOutputs):
        w = wp.tid()
        if not resets_world(force_all, out, w):
            return
        d = env.d
        st = env.st
        for i in range(d.qvel.shape[1]):
            d.qvel[w, i] = 0.0
            d.warm_start[w, i] = 0.0
        for u in range(d.ctrl.shape[1]):
            d.ctrl[w, u] = 0.0
        for i in range(st.action.shape[1]):
            st.action[w, i] = 0.0
            st.prev_action[w, i] = 0.0
        for f in range(st.air_time.shape[1]):
            st.air_time[w, f] = 0.0
            st.contact_time[w, f] = 0.0
        for g in range(NUM_GROUPS):
            st.collision_hits[w, g] = 0
        st.fresh[w] = 1
        rng = events_reset(env, w, stream(rng_state, w, RESET), reset_params)
        rng = draw_command(env.p, st, w, rng)
        rng = restart_intervals(timers, w, rng)
        ep.length[w] = 0
        if force_all != 0 and stagger != 0:  # rsl_rl's init_at_random_ep_len: the time limits fall apart
            ep.length[w] = wp.int32(wp.randi(rng, 0, env.p.episode_length))
        ep.total_return[w] = 0.0
        ep.errors[w, 0] = 0.0
        ep.errors[w, 1] = 0.0

    @wp.kernel(enable_backward=False, module="unique")
    def start_legged_worlds(env: LeggedEnv, rng_state: wp.array[wp.int32], startup_params: Startup):
        """The startup events of every world; the env then recomputes the model constants derived from them."""
        w = wp.tid()
        events_startup(env, w, stream(rng_state, w, STARTUP), startup_params)

    _KERNELS[key] = reset_legged_worlds, start_legged_worlds
    return _KERNELS[key]


_KERNELS: dict = {}
