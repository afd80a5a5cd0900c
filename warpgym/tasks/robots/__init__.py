"""warpgym's own Ant and Humanoid (the robots family): Isaac Gym's task definitions on Newton's model of their MJCF
files, each a frozen dataclass of every number its kernels read (``base.LocomotionTask``)."""

from warpgym.tasks.robots.ant import ANT
from warpgym.tasks.robots.base import LocomotionTask
from warpgym.tasks.robots.humanoid import HUMANOID
from warpgym.tasks.names import imported

TASKS: dict[str, LocomotionTask] = {"ant": ANT, "humanoid": HUMANOID}


def get_task(name) -> LocomotionTask:
    """A robots' task by name (any letter case), or ``"module:Name"`` (the module imported first: it registers the
    task)."""
    if isinstance(name, LocomotionTask):
        return name
    key = str(imported(name)).lower()
    if key not in TASKS:
        raise ValueError(f"unknown task {name!r}: choose one of {[t.name for t in TASKS.values()]}")
    return TASKS[key]


def trained_task(env_args: dict) -> LocomotionTask:
    """The task a run or checkpoint recorded in its ``env_args``: its physics as recorded (a setting added
    since then off, ``warpgym.sim.physics.recorded``) and its substeps, not today's defaults."""
    from warpgym.sim.physics import recorded

    task = get_task(env_args["task"])
    return task.replace(physics=recorded(env_args.get("physics")), substeps=env_args.get("substeps") or task.substeps)


__all__ = ["ANT", "HUMANOID", "TASKS", "LocomotionTask", "get_task", "trained_task"]
