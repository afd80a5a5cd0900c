"""Transitions of every env on the device, ``capacity`` steps per env in a ring, sampled with n-step returns.

Each step stores the observation acted on, the action, the reward, the true next observation (the episode's last
one where it ended: the env's ``final_obs``, not the next episode's first), whether the episode terminated (no
bootstrap) or ended at all (terminated or cut by the time limit), and the episode's number per env (goal relabelling
looks ahead within an episode). The write position and the count live on the device, so that adding and sampling
never wait on the host and can be captured in a CUDA graph.
"""

from __future__ import annotations

import torch


class ReplayBuffer:
    def __init__(self, capacity: int, num_envs: int, num_obs: int, num_actions: int, device: torch.device,
                 num_critic_obs: int = 0, goal_size: int = 0):
        self.capacity, self.num_envs, self.device = capacity, num_envs, device
        t, n = capacity, num_envs

        def z(*shape, dtype=torch.float32):
            return torch.zeros(*shape, dtype=dtype, device=device)

        self.obs, self.next_obs = z(t, n, num_obs), z(t, n, num_obs)
        self.actions = z(t, n, num_actions)
        self.rewards = z(t, n)
        self.terminated = z(t, n, dtype=torch.bool)
        self.ended = z(t, n, dtype=torch.bool)
        self.episode = z(t, n, dtype=torch.long)
        # an asymmetric critic's observations, kept as the policy's are (None: the critic reads the policy's)
        self.critic_obs = z(t, n, num_critic_obs) if num_critic_obs else None
        self.next_critic_obs = z(t, n, num_critic_obs) if num_critic_obs else None
        # a goal-conditioned env's achieved goal after each step (agents.sac.relabel)
        self.achieved = z(t, n, goal_size) if goal_size else None
        self.pos = torch.zeros((), dtype=torch.long, device=device)  # the next step's slot
        self.size = torch.zeros((), dtype=torch.long, device=device)  # steps held per env, at most capacity
        self._episode_now = z(n, dtype=torch.long)  # each env's episode in progress

    def add(self, obs: torch.Tensor, actions: torch.Tensor, rewards: torch.Tensor, next_obs: torch.Tensor,
            terminated: torch.Tensor, ended: torch.Tensor, critic_obs: torch.Tensor | None = None,
            next_critic_obs: torch.Tensor | None = None, achieved: torch.Tensor | None = None) -> None:
        """One step of every env, at the device-held position (the same launches each step: capturable)."""
        at = self.pos.reshape(1)
        pairs = [(self.obs, obs), (self.actions, actions), (self.rewards, rewards), (self.next_obs, next_obs),
                 (self.terminated, terminated), (self.ended, ended), (self.episode, self._episode_now)]
        if self.critic_obs is not None:
            pairs += [(self.critic_obs, critic_obs), (self.next_critic_obs, next_critic_obs)]
        if self.achieved is not None:
            pairs.append((self.achieved, achieved))
        for buffer, value in pairs:
            buffer.index_copy_(0, at, value.to(buffer.dtype)[None])
        self._episode_now += ended.long()
        self.pos.copy_((self.pos + 1) % self.capacity)
        self.size.copy_(torch.clamp(self.size + 1, max=self.capacity))

    def draw(self, batch: int, uniform: torch.Tensor | None = None) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """``batch`` transitions uniformly over every env and held step: (slot, env, steps from the slot to the
        newest, that slot included). ``uniform``: (batch, 2) draws in [0, 1) to use instead of fresh ones."""
        u = torch.rand(batch, 2, device=self.device) if uniform is None else uniform
        env = (u[:, 0] * self.num_envs).long().clamp(max=self.num_envs - 1)
        age = (u[:, 1] * self.size).long().clamp(max=self.size - 1)  # 0: the oldest step held
        slot = (self.pos - self.size + age) % self.capacity
        return slot, env, self.size - age

    def sample(self, batch: int, n_step: int = 1, gamma: float = 0.99,
               uniform: torch.Tensor | None = None) -> dict[str, torch.Tensor]:
        """A batch with n-step returns: ``reward`` sums up to ``n_step`` discounted rewards, stopping after the step
        where the episode ended or at the newest step held; ``next_obs`` follows the last step summed; ``discount``
        is gamma to the power of the steps summed, 0 where that step terminated the episode (no bootstrap)."""
        slot, env, ahead = self.draw(batch, uniform)
        out = {"slot": slot, "env": env, "ahead": ahead, "obs": self.obs[slot, env], "actions": self.actions[slot, env]}
        if self.critic_obs is not None:
            out["critic_obs"] = self.critic_obs[slot, env]
        if n_step == 1:
            last, reward, steps = slot, self.rewards[slot, env], torch.ones_like(slot)
        else:
            offsets = torch.arange(n_step, device=self.device)
            slots = (slot[:, None] + offsets) % self.capacity  # (B, n)
            held = offsets[None] < ahead[:, None]
            ended = self.ended[slots, env[:, None]]
            # a step counts if it is held and no earlier step of the window ended the episode
            before = torch.cat([torch.zeros_like(ended[:, :1]), ended[:, :-1]], dim=1).long().cumsum(1) > 0
            counts = held & ~before
            steps = counts.long().sum(1)  # at least 1: the drawn step itself always counts
            powers = gamma ** offsets.float()
            reward = (self.rewards[slots, env[:, None]] * powers * counts).sum(1)
            last = slots.gather(1, (steps - 1)[:, None]).squeeze(1)
        out["reward"] = reward
        out["next_obs"] = self.next_obs[last, env]
        if self.next_critic_obs is not None:
            out["next_critic_obs"] = self.next_critic_obs[last, env]
        out["discount"] = (gamma ** steps.float()) * (~self.terminated[last, env]).float()
        out["steps"] = steps
        return out
