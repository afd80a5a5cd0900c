"""Task definitions, one frozen dataclass per task holding every number the kernels use: warpgym's own Ant and
Humanoid here (``TASKS``), Gymnasium's suite in ``suite/``, mjlab's legged tasks as tables of terms in ``legged/``
(``terms.py``); every task of every family in ``registry.py``."""

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


def trained_task(env_args: dict) -> LocomotionTask:
    """The task a run or checkpoint recorded in its ``env_args``: its physics as recorded (a setting added
    since then off, ``warpgym.sim.physics.recorded``) and its substeps, not today's defaults."""
    from warpgym.sim.physics import recorded

    task = get_task(env_args["task"])
    return task.replace(physics=recorded(env_args.get("physics")), substeps=env_args.get("substeps") or task.substeps)


__all__ = ["ANT", "HUMANOID", "TASKS", "LocomotionTask", "get_task", "trained_task"]
