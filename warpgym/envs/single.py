"""One world of a vector env as a plain ``gymnasium.Env`` with numpy in and out, for evaluation and inspection.

A family's single env is a subclass in the family's own module (``LocomotionEnv`` in envs/robots.py, ``SuiteEnv``
in envs/suite.py, ``LeggedEnv`` in envs/legged.py) that names its vector env and, where it has more to say per
step, adds it to ``info`` (``_extra``)."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch


class SingleEnv(gym.Env):
    """``num_envs=1`` of ``vec_class``. ``render_mode="rgb_array"``: ``render()`` returns one frame;
    ``"human"``: a viewer window (needs a display)."""

    vec_class: type  # the family's vector env, set by each subclass

    def __init__(self, task, device: str = "cpu", seed: int = 0, render_mode=None, **kwargs):
        self._vec = self.vec_class(task, num_envs=1, device=device, seed=seed, render_mode=render_mode, **kwargs)
        self.render_mode = render_mode
        self.metadata = self._vec.metadata
        self.task = self._vec.task
        self.observation_space = self._vec.single_observation_space
        self.action_space = self._vec.single_action_space

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        obs, _ = self._vec.reset(seed=seed)
        return obs[0].cpu().numpy().copy(), {}

    def step(self, action):
        a = torch.as_tensor(np.asarray(action, dtype=np.float32).reshape(1, -1), device=self._vec.device)
        obs, reward, terminated, truncated, info = self._vec.step(a)
        done = bool(terminated[0] or truncated[0])
        # the vector env has already started the next episode; report the one that ended
        out = info["final_obs"][0] if done else obs[0]
        extra = {key: float(value[0]) for key, value in info.items()
                 if isinstance(value, torch.Tensor) and value.dim() == 1 and key.startswith(("reward_", "x_", "y_"))}
        extra.update(nan_actions=int(info["nan_actions"][0]), diverged=bool(info["diverged"][0]))
        if done:
            extra["episode"] = {key: float(v[0]) for key, v in info["episode"].items() if not key.startswith("_")}
            extra["episode"]["l"] = int(extra["episode"]["l"])
        extra.update(self._extra(info, done))
        return out.cpu().numpy().copy(), float(reward[0]), bool(terminated[0]), bool(truncated[0]), extra

    def _extra(self, info: dict, done: bool) -> dict:
        """What a family adds to a step's ``info`` beyond the reward terms and the episode (numpy, world 0)."""
        return {}

    def render(self):
        frames = self._vec.render()
        return frames[0] if frames else None

    def close(self):
        self._vec.close()
