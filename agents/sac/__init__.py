"""The off-policy learner: soft actor-critic with a distributional critic at GPU scale (FastSAC's and FastTD3's
designs, written for agents): a device replay with n-step returns, clipped double Q on categorical distributions,
several updates per env step on large batches, bf16, each env step with its updates one CUDA graph, asymmetric
observations, and hindsight goal relabelling for goal-conditioned envs. It speaks agents.protocol as PPO does."""

from agents.sac.config import SACConfig
from agents.sac.learner import SAC
from agents.sac.networks import DistributionalCritic, SquashedGaussianPolicy, project
from agents.sac.relabel import GoalSpec, goal_spec, relabel
from agents.sac.replay import ReplayBuffer
from agents.sac.runner import OffPolicyRunner

__all__ = ["SAC", "DistributionalCritic", "GoalSpec", "OffPolicyRunner", "ReplayBuffer", "SACConfig",
           "SquashedGaussianPolicy", "goal_spec", "project", "relabel"]
