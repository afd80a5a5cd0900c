"""Environments built on warpgym's simulators: ``LocomotionVecEnv`` (warpgym's Ant and Humanoid, on
Newton), ``SuiteVecEnv`` (Gymnasium's MuJoCo suite) and ``LeggedVecEnv`` (mjlab's legged velocity tasks), both on
MuJoCo Warp; ``make_vec_env`` builds any task's from its registry entry."""

from importlib import import_module

from warpgym.envs.robots import LocomotionVecEnv


def entry_point(path: str):
    """The class a registry entry names, "module:Class"."""
    module, _, name = path.partition(":")
    return getattr(import_module(module), name)


def make_vec_env(task, for_learner: bool = True, **kwargs):
    """The vector env of a task, a name or a task definition (warpgym.tasks.registry). With ``for_learner``,
    the env a learner trains on: Gymnasium's tasks ("Hopper-v5", ...) then take actions in [-1, 1] mapped onto
    their control ranges (``SuiteVecEnv``'s ``unit_actions``), as the learner adapters and ``warpgym train`` use them;
    warpgym's own tasks always act in [-1, 1]. A keyword given here wins."""
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    entry = task_entry(getattr(task, "name", task))
    return entry_point(entry.vector_entry_point)(task, **{**(dict(entry.learner_kwargs) if for_learner else {}),
                                                          **kwargs})


__all__ = ["LocomotionVecEnv", "entry_point", "make_vec_env"]
