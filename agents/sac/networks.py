"""The off-policy learner's networks: a tanh-squashed Gaussian policy whose mean is a module of its own (what
evaluation plays and export writes), and an ensemble of distributional critics, each a categorical distribution over
returns on a fixed support, with the projection of a Bellman target onto that support."""

from __future__ import annotations

import math

import torch
from torch import nn
from torch.nn import functional as F


def hidden_layers(sizes: list[int], layer_norm: bool) -> nn.Sequential:
    """Linear, LayerNorm (or nothing), SiLU for every step of ``sizes``: a trunk that ends in an activation."""
    layers: list[nn.Module] = []
    for a, b in zip(sizes[:-1], sizes[1:]):
        layers += [nn.Linear(a, b), nn.LayerNorm(b) if layer_norm else nn.Identity(), nn.SiLU()]
    return nn.Sequential(*layers)


class MeanAction(nn.Module):
    """observation -> tanh(mean): the deterministic policy, in [-1, 1]. Evaluation plays it, and ``agents.export``
    writes it as PPO's actor is written."""

    def __init__(self, num_obs: int, num_actions: int, dims: tuple[int, ...], layer_norm: bool):
        super().__init__()
        self.trunk = hidden_layers([num_obs, *dims], layer_norm)
        self.mean = nn.Linear(dims[-1], num_actions)
        # a policy that starts at the centre of the action range, its first actions the noise's
        nn.init.zeros_(self.mean.weight)
        nn.init.zeros_(self.mean.bias)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return torch.tanh(self.mean(self.trunk(obs)))


class SquashedGaussianPolicy(nn.Module):
    """SAC's policy: a Gaussian of state-dependent mean and log-std (squashed into [log_std_min, log_std_max]),
    its sample passed through tanh, the log-probability corrected for the squashing."""

    def __init__(self, num_obs: int, num_actions: int, dims: tuple[int, ...], layer_norm: bool = True,
                 log_std_min: float = -5.0, log_std_max: float = 0.0):
        super().__init__()
        self.actor = MeanAction(num_obs, num_actions, dims, layer_norm)
        self.log_std = nn.Linear(dims[-1], num_actions)
        nn.init.zeros_(self.log_std.weight)
        nn.init.zeros_(self.log_std.bias)
        self.log_std_min, self.log_std_max = float(log_std_min), float(log_std_max)

    def distribution(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The pre-squash Gaussian's mean and log-std."""
        h = self.actor.trunk(obs)
        squashed = torch.tanh(self.log_std(h))
        log_std = self.log_std_min + 0.5 * (self.log_std_max - self.log_std_min) * (squashed + 1.0)
        return self.actor.mean(h), log_std

    def sample(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """A reparameterised action in (-1, 1) and its log-probability (one value per row)."""
        mean, log_std = self.distribution(obs)
        noise = torch.randn_like(mean)
        u = mean + log_std.exp() * noise
        # log N(u) - log(1 - tanh(u)^2), the latter as 2 (log 2 - u - softplus(-2u)): exact where tanh saturates
        log_prob = (-0.5 * noise * noise - log_std - 0.5 * math.log(2 * math.pi)
                    - 2.0 * (math.log(2.0) - u - F.softplus(-2.0 * u))).sum(-1)
        return torch.tanh(u), log_prob

    def act_deterministic(self, obs: torch.Tensor) -> torch.Tensor:
        return self.actor(obs)


class DistributionalCritic(nn.Module):
    """``ensemble`` Q networks on (observation, action), each giving the logits of a categorical distribution over
    ``num_atoms`` returns evenly spaced on [v_min, v_max]."""

    def __init__(self, num_obs: int, num_actions: int, dims: tuple[int, ...], num_atoms: int, v_min: float,
                 v_max: float, layer_norm: bool = True, ensemble: int = 2):
        super().__init__()
        self.nets = nn.ModuleList(
            nn.Sequential(hidden_layers([num_obs + num_actions, *dims], layer_norm), nn.Linear(dims[-1], num_atoms))
            for _ in range(ensemble))
        self.register_buffer("support", torch.linspace(v_min, v_max, num_atoms))
        self.v_min, self.v_max = float(v_min), float(v_max)

    def forward(self, obs: torch.Tensor, actions: torch.Tensor) -> torch.Tensor:
        """Logits, (ensemble, batch, num_atoms)."""
        x = torch.cat([obs, actions], dim=-1)
        return torch.stack([net(x) for net in self.nets])

    def values(self, logits: torch.Tensor) -> torch.Tensor:
        """The expected return of each distribution: (..., num_atoms) logits -> (...)."""
        return (logits.float().softmax(-1) * self.support).sum(-1)


def project(probs: torch.Tensor, reward: torch.Tensor, discount: torch.Tensor, support: torch.Tensor) -> torch.Tensor:
    """The distribution of ``reward + discount * Z`` (Z distributed as ``probs`` over ``support``) projected back onto
    ``support`` (C51's projection): each shifted atom's mass split between the two atoms around it in proportion to
    its distance from each, values beyond the support's ends clipped to them. (B, A) probs, (B,) reward and
    discount (0 where the episode ended: no bootstrap) -> (B, A), each row summing to 1."""
    atoms = support.shape[0]
    v_min, v_max = support[0], support[-1]
    spacing = (v_max - v_min) / (atoms - 1)
    shifted = (reward[:, None] + discount[:, None] * support[None]).clamp(v_min, v_max)
    position = (shifted - v_min) / spacing  # in [0, atoms - 1]
    lower = position.floor().clamp(0, atoms - 1)
    upper_weight = position - lower  # 0 where an atom lands on one exactly (the last one included)
    upper = (lower + 1).clamp(max=atoms - 1)
    out = torch.zeros_like(probs)
    out.scatter_add_(1, lower.long(), probs * (1.0 - upper_weight))
    out.scatter_add_(1, upper.long(), probs * upper_weight)
    return out
