"""Gymnasium ids: ``warpgym/Ant-v0`` and ``warpgym/Humanoid-v0``."""

from __future__ import annotations

import gymnasium as gym

IDS = {"warpgym/Ant-v0": "Ant", "warpgym/Humanoid-v0": "Humanoid"}


def register_envs() -> None:
    for env_id, task in IDS.items():
        if env_id in gym.registry:
            continue
        gym.register(
            id=env_id,
            entry_point="warpgym.envs.single:LocomotionEnv",
            vector_entry_point="warpgym.envs.locomotion:LocomotionVecEnv",
            max_episode_steps=1000,
            kwargs={"task": task},
        )
