"""Gymnasium's MuJoCo suite (v5), task by task: ``SUITE`` maps each id to its default definition."""

from warpgym.tasks.suite.ant import AntV5
from warpgym.tasks.suite.base import GymTask
from warpgym.tasks.suite.half_cheetah import HalfCheetah
from warpgym.tasks.suite.hopper import Hopper
from warpgym.tasks.suite.humanoid import HumanoidV5
from warpgym.tasks.suite.humanoid_standup import HumanoidStandup
from warpgym.tasks.suite.inverted_double_pendulum import InvertedDoublePendulum
from warpgym.tasks.suite.inverted_pendulum import InvertedPendulum
from warpgym.tasks.suite.pusher import Pusher
from warpgym.tasks.suite.reacher import Reacher
from warpgym.tasks.suite.swimmer import Swimmer
from warpgym.tasks.suite.walker2d import Walker2d
from warpgym.tasks.names import imported

SUITE: dict[str, GymTask] = {t.name: t for t in (
    InvertedPendulum(), InvertedDoublePendulum(), Reacher(), Pusher(), Swimmer(), HalfCheetah(), Hopper(),
    Walker2d(), AntV5(), HumanoidV5(), HumanoidStandup())}


def get_suite_task(name) -> GymTask:
    """A suite task by name, or ``"module:Name"`` (the module imported first: it registers the task)."""
    if isinstance(name, GymTask):
        return name
    name = imported(name)
    if name not in SUITE:
        raise ValueError(f"unknown task {name!r}: Gymnasium's MuJoCo suite here is {list(SUITE)}")
    return SUITE[name]


__all__ = ["SUITE", "GymTask", "get_suite_task"]
