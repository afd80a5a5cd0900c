"""Legged robots following a velocity command, as mjlab defines them: ``LEGGED`` maps each id to its default
definition."""

from warpgym.tasks.legged.base import LeggedTask
from warpgym.tasks.legged.g1 import G1VelocityFlat, G1VelocityRough
from warpgym.tasks.legged.go1 import Go1VelocityFlat, Go1VelocityRough
from warpgym.tasks.names import imported

LEGGED: dict[str, LeggedTask] = {t.name: t for t in (Go1VelocityFlat(), G1VelocityFlat(), Go1VelocityRough(),
                                                      G1VelocityRough())}


def get_legged_task(name) -> LeggedTask:
    """A legged task by name, or ``"module:Name"`` (the module imported first: it registers the task)."""
    if isinstance(name, LeggedTask):
        return name
    name = imported(name)
    if name not in LEGGED:
        raise ValueError(f"unknown task {name!r}: the legged velocity tasks are {list(LEGGED)}")
    return LEGGED[name]


__all__ = ["LEGGED", "LeggedTask", "get_legged_task"]
