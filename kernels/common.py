"""What every family of tasks uses alike: the outputs a step returns, the reset noise's random state,
the running counts of faults (agents.protocol), the layout of an observation group of terms and the timers of a
task's interval events."""

import warp as wp

# Nothing differentiates through these kernels; skipping adjoint code shortens their compile.
wp.set_module_options({"enable_backward": False})


@wp.struct
class StepOutputs:
    """What env.step() returns, written in place."""

    obs: wp.array2d[float]  # (N, O) after a reset: the new episode's first observation
    final_obs: wp.array2d[float]  # (N, O) the observation an episode ended on
    reward: wp.array[float]  # (N,)
    terminated: wp.array[wp.bool]  # (N,) fell, or the state is no longer finite
    truncated: wp.array[wp.bool]  # (N,) reached the episode length (Gymnasium's TimeLimit: terminated or not)
    time_outs: wp.array[wp.bool]  # (N,) truncated and not terminated: the episodes a learner bootstraps
    done: wp.array[wp.bool]  # (N,) terminated or truncated
    diverged: wp.array[wp.bool]  # (N,) the physics blew up (NaN/inf or beyond max_speed)


@wp.func
def resets_world(force_all: int, out: StepOutputs, w: int):
    """Whether a reset kernel resets world ``w``: every world on an explicit reset() (which ends no episode, so
    the step's flags are cleared), else the worlds whose episode this step ended."""
    if force_all != 0:
        out.terminated[w] = False
        out.truncated[w] = False
        out.time_outs[w] = False
        out.done[w] = False
        return True
    return out.done[w]


@wp.func
def state_is_finite(qpos: wp.array2d[float], qvel: wp.array2d[float], w: int):
    """Whether world ``w``'s MuJoCo state (qpos, qvel) is finite: a world whose physics blew up is ended and reset."""
    for i in range(qpos.shape[1]):
        if not wp.isfinite(qpos[w, i]):
            return False
    for i in range(qvel.shape[1]):
        if not wp.isfinite(qvel[w, i]):
            return False
    return True


@wp.func
def stream(rng_state: wp.array[wp.int32], env: int, purpose: int):
    """Fresh random numbers per (seed, step, env) from device counters, so that a replayed graph draws new ones;
    one stream per ``purpose``, so that two kernels of one step never draw the same numbers for an env."""
    step_rng = wp.rand_init(rng_state[0], rng_state[1])
    return wp.rand_init(wp.randi(step_rng) + purpose * 7919, env)


@wp.func
def env_rng(rng_state: wp.array[wp.int32], env: int):
    return stream(rng_state, env, 0)


@wp.kernel
def advance_rng(rng_state: wp.array[wp.int32]):  # (2,): seed, step counter
    rng_state[1] = rng_state[1] + 1


@wp.kernel
def count_faults(
    nan_actions: wp.array[wp.int32],  # (N,) non-finite action entries this step
    diverged: wp.array[wp.bool],  # (N,) the world blew up this step and was reset
    overflowed: wp.array[wp.int32],  # (N,) substeps of this step that dropped constraints or contacts
    totals: wp.array[wp.int64],  # (3,) in/out: running sums of the three, since the env was built
):
    env = wp.tid()
    if nan_actions[env] > 0:
        wp.atomic_add(totals, 0, wp.int64(nan_actions[env]))
    if diverged[env]:
        wp.atomic_add(totals, 1, wp.int64(1))
    if overflowed[env] > 0:
        wp.atomic_add(totals, 2, wp.int64(overflowed[env]))


@wp.struct
class ObsLayout:
    """How each observation term of a group is written, by the term's place in its table."""

    size: wp.array[wp.int32]  # (K,) entries
    noise: wp.array[float]  # (K,) uniform noise in [-noise, noise] (0: none)
    clip: wp.array[wp.int32]  # (K,) 1: clamp into [lo, hi]
    lo: wp.array[float]  # (K,)
    hi: wp.array[float]  # (K,)
    scale: wp.array[float]  # (K,) after noise and clip, as mjlab orders them
    history: wp.array[wp.int32]  # (K,) frames the observation holds of the term, oldest first (1: this one)
    hist_at: wp.array[wp.int32]  # (K,) where a term with history keeps its frames in ``hist``
    hist: wp.array2d[float]  # (N, sum of size x history of the terms with history; at least 1)


@wp.struct
class Intervals:
    """The timers of a task's interval events, by the event's place among them (E of them)."""

    lo: wp.array[float]  # (E,) seconds between an event's runs, uniform in [lo, hi]
    hi: wp.array[float]  # (E,)
    left: wp.array2d[float]  # (N, max(E, 1)) seconds to each event's next run


@wp.func
def restart_intervals(iv: Intervals, w: int, rng: wp.uint32) -> wp.uint32:
    """A reset world's time to each interval event's next run, drawn afresh (mjlab's event manager at a reset)."""
    for k in range(iv.lo.shape[0]):
        iv.left[w, k] = wp.randf(rng, iv.lo[k], iv.hi[k])
    return rng
