"""Environments built on warpgym's simulators: ``LocomotionVecEnv`` (warpgym's Ant and Humanoid, on
Newton) and ``SuiteVecEnv`` (Gymnasium's MuJoCo suite, on MuJoCo Warp)."""

from warpgym.envs.locomotion import LocomotionVecEnv


def make_vec_env(task: str, for_learner: bool = True, **kwargs):
    """The vector env of a task name. Gymnasium's tasks ("Hopper-v5", ...) take actions in [-1, 1]
    mapped onto their control ranges when ``for_learner`` (``SuiteVecEnv``'s ``unit_actions``), as the
    learner adapters and ``warpgym train`` use them; warpgym's own tasks always act in [-1, 1]."""
    from warpgym.tasks.suite import SUITE  # noqa: PLC0415

    if task in SUITE:
        from warpgym.envs.suite import SuiteVecEnv  # noqa: PLC0415

        return SuiteVecEnv(task, unit_actions=kwargs.pop("unit_actions", for_learner), **kwargs)
    return LocomotionVecEnv(task, **kwargs)


__all__ = ["LocomotionVecEnv", "make_vec_env"]
