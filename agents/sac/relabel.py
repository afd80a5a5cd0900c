"""Hindsight goal relabelling (Andrychowicz et al. 2017, "future"): a sampled transition of a goal-conditioned env
has its goal replaced, with probability ``fraction``, by the goal the same episode achieved at that step or a later
one, and its reward recomputed by the env's own ``compute_reward``: failed episodes teach how to reach where they
went.

A goal-conditioned env (Gymnasium's goal API, flattened for the learner) declares ``goal_layout``, where the desired
goal sits in its flat observations: ``{"obs": (start, end)}``, with ``"critic_obs"`` too for an asymmetric critic;
``compute_reward(achieved_goal, desired_goal, info)``, vectorised over rows of device tensors; and in every step's
info ``info["achieved_goal"]``, the goal achieved by that step (its final state's where the episode ended).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import torch

from agents.sac.replay import ReplayBuffer


@dataclass(frozen=True)
class GoalSpec:
    obs: tuple[int, int]  # the desired goal's columns in the policy's observation
    critic_obs: tuple[int, int] | None  # ... and in the critic's, where it has its own
    compute_reward: Callable
    max_ahead: int  # the longest episode: how far ahead of a step its episode can go on

    @property
    def size(self) -> int:
        return self.obs[1] - self.obs[0]


def goal_spec(env, max_episode_steps: int) -> GoalSpec | None:
    """The env's goal layout (module docstring), checked, or None for an env without goals."""
    layout = getattr(env, "goal_layout", None)
    if layout is None:
        return None
    reward = getattr(env, "compute_reward", None)
    if not callable(reward):
        raise TypeError(f"{type(env).__name__} declares goal_layout but has no compute_reward(achieved_goal, "
                        "desired_goal, info): give it one, vectorised over rows (agents.sac.relabel)")
    spans = {}
    for key in ("obs", "critic_obs"):
        span = layout.get(key)
        if span is None:
            continue
        start, end = (int(v) for v in span)
        if not 0 <= start < end:
            raise ValueError(f"{type(env).__name__}.goal_layout[{key!r}]={span!r}: give (start, end) columns with "
                             "0 <= start < end")
        spans[key] = (start, end)
    if "obs" not in spans:
        raise ValueError(f"{type(env).__name__}.goal_layout={layout!r} has no 'obs' span: say where the desired goal "
                         "sits in the policy's observation")
    critic = spans.get("critic_obs")
    if critic is not None and critic[1] - critic[0] != spans["obs"][1] - spans["obs"][0]:
        raise ValueError(f"{type(env).__name__}.goal_layout: spans {spans['obs']} and {critic} differ in width")
    return GoalSpec(spans["obs"], critic, reward, int(max_episode_steps))


def relabel(batch: dict, buffer: ReplayBuffer, spec: GoalSpec, fraction: float,
            uniform: torch.Tensor | None = None) -> dict:
    """``batch`` (ReplayBuffer.sample's, one-step) with goals replaced in place of a share ``fraction`` of its rows
    (module docstring). ``uniform``: (batch, 2) draws in [0, 1) to use instead of fresh ones (which future step,
    whether to relabel)."""
    slot, env, ahead = batch["slot"], batch["env"], batch["ahead"]
    u = torch.rand(slot.shape[0], 2, device=slot.device) if uniform is None else uniform
    horizon = min(spec.max_ahead, buffer.capacity)
    offsets = torch.arange(horizon, device=slot.device)
    slots = (slot[:, None] + offsets) % buffer.capacity
    episode = buffer.episode[slots, env[:, None]]
    # the steps from this one to its episode's last held one
    same = (episode == episode[:, :1]) & (offsets[None] < ahead[:, None])
    reach = same.long().cumprod(1).sum(1)  # at least 1: the step itself
    pick = (u[:, 0] * reach).long().clamp(max=reach - 1)
    future = (slot + pick) % buffer.capacity
    chosen = u[:, 1] < fraction
    new_goal = buffer.achieved[future, env]
    s, e = spec.obs
    goal = torch.where(chosen[:, None], new_goal, batch["obs"][:, s:e])
    for key in ("obs", "next_obs"):
        batch[key] = torch.cat([batch[key][:, :s], goal, batch[key][:, e:]], dim=1)
    if spec.critic_obs is not None:
        cs, ce = spec.critic_obs
        for key in ("critic_obs", "next_critic_obs"):
            batch[key] = torch.cat([batch[key][:, :cs], goal, batch[key][:, ce:]], dim=1)
    achieved = buffer.achieved[slot, env]
    batch["reward"] = torch.where(chosen, spec.compute_reward(achieved, goal, {}).to(batch["reward"].dtype),
                                  batch["reward"])
    batch["relabelled"] = chosen
    return batch
