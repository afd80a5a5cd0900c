"""Gymnasium ids: warpgym's own tasks (``warpgym/Ant-v0``, ``warpgym/Humanoid-v0``) and Gymnasium's
MuJoCo suite (``warpgym/Hopper-v5``, ... : the same names and versions as Gymnasium's), from the task
registry (warpgym.tasks.registry)."""

from __future__ import annotations

import gymnasium as gym


def register_envs() -> None:
    from warpgym.tasks.registry import REGISTRY  # noqa: PLC0415

    for name, entry in REGISTRY.items():
        if entry.gym_id not in gym.registry:
            gym.register(id=entry.gym_id, entry_point=entry.single_entry_point,
                         vector_entry_point=entry.vector_entry_point, max_episode_steps=entry.episode_length,
                         kwargs={"task": name})
