"""A user's own terms, in a module outside warpgym (tests/test_user_terms.py trains with them): a reward, an
observation and an event written against the legged tasks' contract (``kernels.legged.params.LeggedEnv``), and a
reward and a termination against the suite's (``kernels.suite.params.SuiteState``) and the robots'
(``kernels.robots.buffers.RobotState``); tests/user_task.py registers a task with each."""

import warp as wp

from kernels.legged.params import LeggedEnv
from kernels.robots.buffers import RobotState
from kernels.suite.params import SuiteState
from warpgym.tasks.terms import Event, Observation, Reward, Termination


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


@wp.func
def action_energy(env: SuiteState, w: int) -> float:
    """|action|^2 of the step, as Gymnasium's control cost reads it, written again so a test can compare."""
    total = float(0.0)
    for a in range(env.ep.actions.shape[1]):
        total += env.ep.actions[w, a] * env.ep.actions[w, a]
    return total


@wp.struct
class Height:
    below: float  # [m]


@wp.func
def torso_below(env: SuiteState, w: int, p: Height) -> bool:
    """the Hopper's torso (qpos[1], its height) under ``below``"""
    return env.d.qpos[w, 1] < p.below


SUITE_REWARDS = {"user_energy": Reward(action_energy, weight=-2e-3)}
SUITE_TERMINATIONS = {"torso_below": Termination(torso_below, params={"below": 0.9})}


@wp.func
def upright(env: RobotState, w: int) -> float:
    """the torso's up projection (Isaac Gym's up_proj, the observation's entry 10)"""
    return env.obs[w, 10]


@wp.struct
class Ceiling:
    height: float  # [m]


@wp.func
def torso_above(env: RobotState, w: int, p: Ceiling) -> bool:
    """the torso (the observation's entry 0, its height) over ``height``"""
    return env.obs[w, 0] > p.height


ROBOT_REWARDS = {"user_upright": Reward(upright, weight=0.25)}
ROBOT_TERMINATIONS = {"torso_above": Termination(torso_above, params={"height": 5.0})}
