"""Collect the next rollout while PPO learns from the last one (``Config.overlap``).

Iteration k collects rollout k with a frozen copy of the policy (the behaviour policy, the weights
after update k-1) on a side CUDA stream, while the main stream runs PPO on rollout k-1; then the
streams join and rollout k moves to the buffer PPO reads. Each rollout is learnt from one update
after the weights that collected it: PPO's ratio divides by the log-probabilities, values and noise
recorded at collection, so it stays the ratio to the policy that acted, as in IMPALA-style
one-step-stale learners.

Only a captured rollout graph runs on the side stream: an eager rollout would launch the env's
kernels on whatever stream the simulator uses, so until the graph exists (and on the CPU) the two
halves run one after the other, with the same lag: the numbers learnt are the same either way.
"""

from __future__ import annotations

import copy
from types import SimpleNamespace

import torch

from agents.actor_critic import ActorCritic
from agents.storage import RolloutStorage

# what PPO reads from a rollout (agents.ppo.PPO._bind and its advantage normalisation)
TRAINED_FIELDS = ("obs", "actions", "log_probs", "values", "means", "returns", "advantages")


class RolloutPipeline:
    """The behaviour policy, the buffer PPO learns from, and the side stream collection runs on."""

    def __init__(self, policy: ActorCritic, storage: RolloutStorage, device: torch.device):
        self.behaviour = copy.deepcopy(policy).requires_grad_(False)
        # only what PPO reads: raw and final observations would double the rollout's largest buffers
        self.fields = TRAINED_FIELDS + (("critic_obs",) if storage.critic_obs is not None else ())
        self.trained = SimpleNamespace(**{"critic_obs": None,
                                          **{f: torch.empty_like(getattr(storage, f)) for f in self.fields}})
        self.trained_log_std = torch.zeros_like(policy.log_std.detach())  # the noise it was drawn with
        self.stream = torch.cuda.Stream(device) if device.type == "cuda" else None
        self.pending = False  # a collected rollout that PPO has not learnt from yet

    @torch.no_grad()
    def sync(self, policy: ActorCritic) -> None:
        """The behaviour policy takes the learner's weights (in place: a captured graph reads them)."""
        torch._foreach_copy_(list(self.behaviour.parameters()), list(policy.parameters()))

    def hand_over(self, collected: RolloutStorage, log_std: torch.Tensor) -> None:
        """Rollout ``collected`` becomes the one PPO learns from next (device copies, no host wait)."""
        torch._foreach_copy_([getattr(self.trained, f) for f in self.fields],
                             [getattr(collected, f) for f in self.fields])
        self.trained_log_std.copy_(log_std)
        self.pending = True
