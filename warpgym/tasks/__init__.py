"""Task definitions: one frozen dataclass per task holds every number the kernels use."""

from warpgym.tasks.ant import ANT
from warpgym.tasks.humanoid import HUMANOID
from warpgym.tasks.locomotion import LocomotionTask

TASKS: dict[str, LocomotionTask] = {"ant": ANT, "humanoid": HUMANOID}


def get_task(name) -> LocomotionTask:
    if isinstance(name, LocomotionTask):
        return name
    key = str(name).lower()
    if key not in TASKS:
        raise ValueError(f"unknown task {name!r}: choose one of {[t.name for t in TASKS.values()]}")
    return TASKS[key]


__all__ = ["ANT", "HUMANOID", "TASKS", "LocomotionTask", "get_task"]
