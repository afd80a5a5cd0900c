"""The velocity command (mjlab's UniformVelocityCommand with its command curriculum): drawn at a reset and when
its timer runs out, then steered each step (a heading world's yaw rate toward its heading target, a standing
world's command held at zero); and mjlab's tracking errors, summed over the episode."""

import warp as wp

from kernels.common import stream
from kernels.legged.frames import heading, root_velocity_b
from kernels.legged.params import FORWARD, HEADING, STANDING, LeggedEpisodes, LeggedParams, LeggedRobot, LeggedState, MjLegged
from kernels.legged.random import COMMAND
from kernels.math import wrap_angle

wp.set_module_options({"enable_backward": False})


@wp.func
def stage(p: LeggedParams, step: int):
    """The command curriculum's stage at env step ``step``: the last whose start has passed."""
    s = int(0)
    for i in range(p.stage_steps.shape[0]):
        if step >= p.stage_steps[i]:
            s = i
    return s


@wp.func
def draw_command(p: LeggedParams, st: LeggedState, w: int, rng: wp.uint32):
    """A new command and the time until the next one (mjlab's _resample and _resample_command). Returns the random
    state after its draws: a function draws from a copy of the caller's."""
    s = stage(p, st.step_count[0])
    st.command_time_left[w] = wp.randf(rng, p.resample_lo, p.resample_hi)
    x = wp.randf(rng, p.stage_ranges[s, 0], p.stage_ranges[s, 1])
    y = wp.randf(rng, p.stage_ranges[s, 2], p.stage_ranges[s, 3])
    z = wp.randf(rng, p.stage_ranges[s, 4], p.stage_ranges[s, 5])
    st.heading_target[w] = wp.randf(rng, p.heading_lo, p.heading_hi)
    kind = int(0)
    # torch's uniform_ draws in [0, 1) and mjlab compares with <=
    if wp.randf(rng) <= p.rel_heading:
        kind = kind | HEADING
    if wp.randf(rng) <= p.rel_standing:
        kind = kind | STANDING
    if wp.randf(rng) <= p.rel_forward:
        kind = kind | FORWARD
        x = wp.max(wp.abs(x), p.forward_min)
        y = 0.0
        z = 0.0
    st.command_kind[w] = kind
    st.command[w, 0] = x
    st.command[w, 1] = y
    st.command[w, 2] = z
    return rng


@wp.func
def steer_command(p: LeggedParams, d: MjLegged, r: LeggedRobot, st: LeggedState, w: int):
    """mjlab's _update_command: a heading world turns toward its target, a standing world's command is zero."""
    kind = st.command_kind[w]
    if (kind & HEADING) != 0:
        s = stage(p, st.step_count[0])
        error = wrap_angle(st.heading_target[w] - heading(d.xquat[w, r.root_body]))
        st.command[w, 2] = wp.clamp(p.heading_stiffness * error, p.stage_ranges[s, 4], p.stage_ranges[s, 5])
    if (kind & STANDING) != 0:
        for i in range(3):
            st.command[w, i] = 0.0


@wp.kernel
def update_commands(p: LeggedParams, r: LeggedRobot, force_all: int, rng_state: wp.array[wp.int32],
                    done: wp.array[wp.bool], d: MjLegged, st: LeggedState, ep: LeggedEpisodes):
    """After the step's forward pass (mjlab's CommandManager.compute): the tracking errors of the command in force
    and the new state, the timers (a world reset this step loses no time), new commands where a timer ran out,
    and the steering."""
    w = wp.tid()
    v, omega = root_velocity_b(d, r, w)
    ex = st.command[w, 0] - v[0]
    ey = st.command[w, 1] - v[1]
    ep.errors[w, 0] = ep.errors[w, 0] + wp.sqrt(ex * ex + ey * ey) / p.max_command_steps
    ep.errors[w, 1] = ep.errors[w, 1] + wp.abs(st.command[w, 2] - omega[2]) / p.max_command_steps
    if force_all == 0 and not done[w]:
        st.command_time_left[w] = st.command_time_left[w] - p.dt
    if st.command_time_left[w] <= 0.0:
        draw_command(p, st, w, stream(rng_state, w, COMMAND))
    steer_command(p, d, r, st, w)
