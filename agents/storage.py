"""Rollout storage (time-major, on the device) and generalised advantage estimation."""

from __future__ import annotations

import torch


class RolloutStorage:
    def __init__(self, horizon: int, num_envs: int, num_obs: int, num_actions: int, device: torch.device,
                 num_critic_obs: int = 0):
        self.horizon, self.num_envs = horizon, num_envs
        t, n = horizon, num_envs

        def z(*shape, dtype=torch.float32):
            return torch.zeros(*shape, dtype=dtype, device=device)

        self.obs = z(t, n, num_obs)  # normalised, as the policy saw them
        self.raw_obs = z(t, n, num_obs)  # as the env returned them; the normaliser learns from these
        self.final_obs = z(t, n, num_obs)  # raw last observation of episodes that ended at step t
        # the critic's own observation (an asymmetric actor-critic), kept as the policy's is; None: the critic
        # reads the policy's
        asym = num_critic_obs > 0
        self.critic_obs = z(t, n, num_critic_obs) if asym else None
        self.raw_critic_obs = z(t, n, num_critic_obs) if asym else None
        self.final_critic_obs = z(t, n, num_critic_obs) if asym else None
        self.truncated = z(t, n)
        self.actions = z(t, n, num_actions)
        self.log_probs = z(t, n)
        self.values = z(t, n)
        self.means = z(t, n, num_actions)
        self.rewards = z(t, n)  # env rewards; scaled and bootstrapped after the rollout
        self.dones = z(t, n)
        self.advantages = z(t, n)
        self.returns = z(t, n)


def compute_gae(rewards, values, dones, last_values, gamma: float, lam: float):
    """Advantages and returns for a (T, N) rollout.

    ``rewards`` must already include the bootstrap of truncated episodes (gamma * V(final_obs));
    ``dones`` is 1 where the episode ended at that step (terminated or truncated), so no value
    flows across an episode boundary. Returns (advantages, returns), both (T, N).
    """
    horizon = rewards.shape[0]
    advantages = torch.empty_like(rewards)
    next_adv = torch.zeros_like(last_values)
    next_values = last_values
    for t in reversed(range(horizon)):
        not_done = 1.0 - dones[t]
        delta = rewards[t] + gamma * next_values * not_done - values[t]
        next_adv = delta + gamma * lam * not_done * next_adv
        advantages[t] = next_adv
        next_values = values[t]
    return advantages, advantages + values
