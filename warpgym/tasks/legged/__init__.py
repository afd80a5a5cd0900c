"""Legged robots following a velocity command, as mjlab defines them: ``LEGGED`` maps each id to its default
definition: mjlab's Go1 and G1 tasks, and the velocity tasks of any robot (``VelocityFlat-v0``, ``VelocityRough-v0``:
the Go1 until ``robot=`` names another, robot_task.py)."""

from warpgym.tasks.legged.base import LeggedTask
from warpgym.tasks.legged.g1 import G1VelocityFlat, G1VelocityRough
from warpgym.tasks.legged.go1 import GO1, Go1VelocityFlat, Go1VelocityRough
from warpgym.tasks.legged.robot_task import velocity_task
from warpgym.tasks.names import imported

LEGGED: dict[str, LeggedTask] = {t.name: t for t in (Go1VelocityFlat(), G1VelocityFlat(), Go1VelocityRough(),
                                                      G1VelocityRough(), velocity_task(GO1),
                                                      velocity_task(GO1, rough=True))}


def get_legged_task(name) -> LeggedTask:
    """A legged task by name, or ``"module:Name"`` (the module imported first: it registers the task)."""
    if isinstance(name, LeggedTask):
        return name
    name = imported(name)
    if name not in LEGGED:
        raise ValueError(f"unknown task {name!r}: the legged velocity tasks are {list(LEGGED)}")
    return LEGGED[name]


def trained_legged_task(env_args: dict) -> LeggedTask:
    """The legged task a run trained, from the ``env_args`` it saved: its task, with the robot it named."""
    task = get_legged_task(env_args["task"])
    return task.replace(robot=env_args["robot"]) if env_args.get("robot") else task


__all__ = ["LEGGED", "LeggedTask", "get_legged_task", "trained_legged_task"]
