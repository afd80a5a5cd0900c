"""warpgym as a numpy vector env, for learners and Gymnasium wrappers written for numpy.

This is the slow path: every step copies the observations, rewards and flags to the host and the
actions back, and on a GPU waits for the step to finish. Use it for CPU learners (SB3) and for
checking an env with Gymnasium's own tools; the torch adapters keep the data on the device.

warpgym already reports finished episodes in ``info["episode"]`` (return ``r``, length ``l``,
forward speed ``s``, masks ``_r``...), the way ``RecordEpisodeStatistics`` does. That wrapper
refuses an info that has the key already: wrap with ``RecordEpisodeStatistics(env,
stats_key="gym_episode")``, or read warpgym's.
"""

from __future__ import annotations

import numpy as np
import torch
from gymnasium.vector import VectorEnv

from warpgym.wrappers.common import base_env


def to_numpy(x):
    """Tensors (nested in dicts) to numpy arrays; anything else unchanged."""
    if isinstance(x, torch.Tensor):
        return x.detach().cpu().numpy()
    if isinstance(x, dict):
        return {k: to_numpy(v) for k, v in x.items()}
    return x


class NumpyVecEnv(VectorEnv):
    """A Gymnasium ``VectorEnv`` with numpy observations, rewards, flags and infos.

    Args:
        env: a warpgym ``LocomotionVecEnv`` (or a Gymnasium wrapper of one).
    """

    def __init__(self, env):
        self.env = env
        self._base = base_env(env)
        b = self._base
        self.num_envs = b.num_envs
        self.single_observation_space, self.single_action_space = b.single_observation_space, b.single_action_space
        self.observation_space, self.action_space = b.observation_space, b.action_space
        self.metadata = dict(b.metadata)
        self.device = b.device

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, info = self.env.reset(seed=seed, options=options)
        return to_numpy(obs).copy(), to_numpy(info)

    def step(self, actions):
        obs, reward, terminated, truncated, info = self.env.step(np.asarray(actions, dtype=np.float32))
        return (to_numpy(obs).copy(), to_numpy(reward).astype(np.float64), to_numpy(terminated).copy(),
                to_numpy(truncated).copy(), to_numpy(info))

    def close(self, **kwargs):
        self.env.close()
