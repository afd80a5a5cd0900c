"""Gaussian actor-critic: two MLPs and a state-independent log standard deviation. The critic may see an
observation of its own (``num_critic_obs``: an asymmetric actor-critic, as rsl_rl's "critic" group): every method
that gives a value then takes it, and falls back to the policy's observation when there is none."""

from __future__ import annotations

import math

import torch
from torch import nn

ACTIVATIONS = {"elu": nn.ELU, "relu": nn.ReLU, "tanh": nn.Tanh}


def mlp(sizes: list[int], activation: str) -> nn.Sequential:
    layers: list[nn.Module] = []
    for i in range(len(sizes) - 1):
        layers.append(nn.Linear(sizes[i], sizes[i + 1]))
        if i < len(sizes) - 2:
            layers.append(ACTIVATIONS[activation]())
    return nn.Sequential(*layers)


class ActorCritic(nn.Module):
    def __init__(self, num_obs: int, num_actions: int, net_dims=(256, 128, 64), activation: str = "elu",
                 init_noise_std: float = 1.0, num_critic_obs: int = 0):
        super().__init__()
        self.actor = mlp([num_obs, *net_dims, num_actions], activation)
        self.critic = mlp([num_critic_obs or num_obs, *net_dims, 1], activation)
        self.log_std = nn.Parameter(torch.full((num_actions,), math.log(init_noise_std)))
        # A small last actor layer starts the policy near zero mean, so early actions are mostly noise.
        nn.init.normal_(self.actor[-1].weight, std=0.01)
        nn.init.zeros_(self.actor[-1].bias)

    def act(self, obs: torch.Tensor, critic_obs: torch.Tensor | None = None):
        """Sample actions; return (actions, log_prob, value, mean)."""
        mean = self.actor(obs)
        std = self.log_std.exp()
        actions = mean + std * torch.randn_like(mean)
        value = self.value(obs if critic_obs is None else critic_obs)
        return actions, gaussian_log_prob(actions, mean, self.log_std), value, mean

    def act_deterministic(self, obs: torch.Tensor) -> torch.Tensor:
        return self.actor(obs)

    def value(self, critic_obs: torch.Tensor) -> torch.Tensor:
        """The value of the critic's observation (the policy's, for a symmetric actor-critic)."""
        return self.critic(critic_obs).squeeze(-1)

    def evaluate(self, obs: torch.Tensor, actions: torch.Tensor, critic_obs: torch.Tensor | None = None):
        """(log_prob of actions, entropy, value, mean) under the current parameters."""
        mean = self.actor(obs)
        log_prob = gaussian_log_prob(actions, mean, self.log_std)
        entropy = (0.5 + 0.5 * math.log(2 * math.pi) + self.log_std).sum().expand(obs.shape[0])
        return log_prob, entropy, self.value(obs if critic_obs is None else critic_obs), mean


def gaussian_log_prob(x: torch.Tensor, mean: torch.Tensor, log_std: torch.Tensor) -> torch.Tensor:
    z = (x - mean) * torch.exp(-log_std)
    return (-0.5 * z * z - log_std - 0.5 * math.log(2 * math.pi)).sum(-1)


def gaussian_kl(mean_old, log_std_old, mean_new, log_std_new) -> torch.Tensor:
    """KL(old || new) of diagonal Gaussians, summed over action dims, one value per sample."""
    var_old = torch.exp(2 * log_std_old)
    var_new = torch.exp(2 * log_std_new)
    return (log_std_new - log_std_old + (var_old + (mean_old - mean_new) ** 2) / (2 * var_new) - 0.5).sum(-1)
