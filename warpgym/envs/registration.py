"""Gymnasium ids: warpgym's own tasks (``warpgym/Ant-v0``, ``warpgym/Humanoid-v0``) and Gymnasium's
MuJoCo suite (``warpgym/Hopper-v5``, ... : the same names and versions as Gymnasium's)."""

from __future__ import annotations

import gymnasium as gym

IDS = {"warpgym/Ant-v0": "Ant", "warpgym/Humanoid-v0": "Humanoid"}


def register_envs() -> None:
    from warpgym.tasks.suite import SUITE  # noqa: PLC0415

    for env_id, task in IDS.items():
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point="warpgym.envs.single:LocomotionEnv",
                         vector_entry_point="warpgym.envs.locomotion:LocomotionVecEnv", max_episode_steps=1000,
                         kwargs={"task": task})
    for name, task in SUITE.items():
        env_id = f"warpgym/{name}"
        if env_id not in gym.registry:
            gym.register(id=env_id, entry_point="warpgym.envs.single:SuiteEnv",
                         vector_entry_point="warpgym.envs.suite:SuiteVecEnv",
                         max_episode_steps=task.episode_length, kwargs={"task": name})
