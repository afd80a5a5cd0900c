"""A user's own terms, in a module outside warpgym (tests/test_user_terms.py trains with them): a reward, an
observation and an event written against the legged tasks' contract (``kernels.legged.params.LeggedEnv``);
tests/user_task.py registers a task with them."""

import warp as wp

from kernels.legged.params import LeggedEnv
from warpgym.tasks.terms import Event, Observation, Reward


@wp.struct
class Scale:
    scale: float


@wp.func
def scaled_action_rate(env: LeggedEnv, w: int, p: Scale) -> float:
    """``scale`` x |action - previous action|^2: warpgym's action_rate_l2 written again, so a test can compare."""
    total = float(0.0)
    for a in range(env.st.action.shape[1]):
        e = env.st.action[w, a] - env.st.prev_action[w, a]
        total += e * e
    return p.scale * total


@wp.func
def base_height(env: LeggedEnv, w: int, i: int) -> float:
    """the base's height above the world's origin [m]"""
    return env.d.xpos[w, env.r.root_body][2]


@wp.struct
class Lift:
    speed: wp.vec2  # [m/s]


@wp.func
def lift_base(env: LeggedEnv, w: int, rng: wp.uint32, p: Lift) -> wp.uint32:
    """the base's upward speed set to a uniform draw [m/s], after the task's own reset events"""
    env.d.qvel[w, env.r.root_dof + 2] = wp.randf(rng, p.speed[0], p.speed[1])
    return rng


REWARDS = {"user_action_rate": Reward(scaled_action_rate, weight=-0.1, params={"scale": 3.0})}
OBSERVATIONS = {"base_height": Observation(base_height, 1)}
EVENTS = {"lift": Event(lift_base, "reset", {"speed": (1.0, 2.0)})}
