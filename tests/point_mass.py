"""A batched point mass in torch alone: the smallest env that speaks agents.protocol.

Each env is a unit mass on a plane pushed by a force in [-1, 1]^2; the reward is minus the distance
to the origin (minus a little effort); episodes last 50 steps and end by truncation only.
"""

from __future__ import annotations

import torch
from gymnasium import spaces


class PointMassVecEnv:
    def __init__(self, num_envs: int = 64, device: str = "cpu", episode_length: int = 50, seed: int = 0):
        self.num_envs = num_envs
        self.device = torch.device(device)
        self.max_episode_steps = episode_length
        self.single_observation_space = spaces.Box(-float("inf"), float("inf"), (4,))
        self.single_action_space = spaces.Box(-1.0, 1.0, (2,))
        self.dt = 0.1
        self.gen = torch.Generator(device=self.device).manual_seed(seed)
        self.pos = torch.zeros(num_envs, 2, device=self.device)
        self.vel = torch.zeros(num_envs, 2, device=self.device)
        self.t = torch.zeros(num_envs, dtype=torch.int32, device=self.device)

    def _obs(self):
        return torch.cat([self.pos, self.vel], dim=1)

    def _reset(self, mask):
        fresh = torch.rand(self.num_envs, 2, device=self.device, generator=self.gen) * 4 - 2
        self.pos = torch.where(mask[:, None], fresh, self.pos)
        self.vel = torch.where(mask[:, None], torch.zeros_like(self.vel), self.vel)
        self.t = torch.where(mask, torch.zeros_like(self.t), self.t)

    def reset(self, seed=None):
        self._reset(torch.ones(self.num_envs, dtype=torch.bool, device=self.device))
        return self._obs(), {}

    def step(self, actions):
        a = actions.clamp(-1, 1)
        self.vel = 0.9 * self.vel + a * self.dt * 5
        self.pos = self.pos + self.vel * self.dt
        self.t += 1
        reward = -self.pos.norm(dim=1) - 0.01 * (a * a).sum(1)
        terminated = torch.zeros(self.num_envs, dtype=torch.bool, device=self.device)
        truncated = self.t >= self.max_episode_steps
        final_obs = self._obs()
        self._reset(truncated)
        return self._obs(), reward, terminated, truncated, {"final_obs": final_obs, "_final_obs": truncated}
