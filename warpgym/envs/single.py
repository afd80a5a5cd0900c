"""One world as a plain ``gymnasium.Env`` with numpy in and out, for evaluation and inspection."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import torch

from warpgym.envs.legged import LeggedVecEnv
from warpgym.envs.robots import LocomotionVecEnv
from warpgym.envs.suite import SuiteVecEnv


class LocomotionEnv(gym.Env):
    """``render_mode="rgb_array"``: ``render()`` returns one frame of the robot; ``"human"``: MuJoCo's
    viewer (needs a display)."""

    metadata = LocomotionVecEnv.metadata
    vec_class = LocomotionVecEnv

    def __init__(self, task="Ant", device: str = "cpu", seed: int = 0, render_mode=None, **kwargs):
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
        return out.cpu().numpy().copy(), float(reward[0]), bool(terminated[0]), bool(truncated[0]), extra

    def render(self):
        frames = self._vec.render()
        return frames[0] if frames else None

    def close(self):
        self._vec.close()


class SuiteEnv(LocomotionEnv):
    """One world of Gymnasium's MuJoCo task (``gym.make("warpgym/Hopper-v5")``): numpy float32 in and out,
    Gymnasium's reward terms in ``info``."""

    vec_class = SuiteVecEnv
    metadata = SuiteVecEnv.metadata

    def __init__(self, task="Hopper-v5", device: str = "cpu", seed: int = 0, render_mode=None, **kwargs):
        super().__init__(task, device, seed, render_mode, **kwargs)


class LeggedEnv(LocomotionEnv):
    """One world of a legged velocity task (``gym.make("warpgym/Go1VelocityFlat-v0")``): numpy in and out, the
    reward terms in ``info``, the critic's observation in ``info["critic_obs"]``."""

    vec_class = LeggedVecEnv
    metadata = LeggedVecEnv.metadata

    def __init__(self, task="Go1VelocityFlat-v0", device: str = "cpu", seed: int = 0, render_mode=None, **kwargs):
        super().__init__(task, device, seed, render_mode, **kwargs)

    def step(self, action):
        obs, reward, terminated, truncated, extra = super().step(action)
        info = self._vec.info
        key = "final_critic_obs" if terminated or truncated else "critic_obs"
        extra["critic_obs"] = info[key][0].cpu().numpy().copy()
        extra["command"] = info["command"][0].cpu().numpy().copy()
        return obs, reward, terminated, truncated, extra
