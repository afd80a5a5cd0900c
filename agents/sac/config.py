"""The off-policy learner's settings (``SACConfig``): soft actor-critic with a distributional critic, many envs and
large batches, as FastSAC (arXiv 2512.01996) and FastTD3 (arXiv 2505.22642) run it on thousands of GPU envs. The
defaults are FastSAC's for humanoids on 4096 envs; a task's preset (warpgym.tasks.presets) changes what its task
needs.

Units: ``steps_per_iteration`` is env steps per env between two logged rows (PPO's ``horizon_len``); ``buffer_size``
is steps kept per env (the replay holds ``buffer_size * num_envs`` transitions); ``batch_size`` is transitions per
gradient step; ``num_updates`` is critic steps per env step; ``policy_frequency`` is critic steps per actor step.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

from agents.config import RunConfig, _is_number, check_positive_ints


@dataclass
class SACConfig(RunConfig):
    agent: str = "AgentSAC"
    env_class: Callable | None = None
    env_args: dict = field(default_factory=dict)
    eval_env_class: Callable | None = None
    eval_env_args: dict = field(default_factory=dict)

    # networks: Linear, LayerNorm, SiLU per hidden layer (layer norm keeps a critic trained at a high update ratio
    # from diverging); the critic is an ensemble of ``num_critics`` categorical distributions over ``num_atoms``
    # returns evenly spaced on [v_min, v_max]
    actor_dims: tuple[int, ...] = (512, 256, 128)
    critic_dims: tuple[int, ...] = (768, 384, 192)
    layer_norm: bool = True
    num_critics: int = 2
    num_atoms: int = 101
    v_min: float = -20.0
    v_max: float = 20.0

    gamma: float = 0.97
    n_step: int = 1  # the returns' steps before bootstrapping (cut at an episode's end)
    tau: float = 0.125  # the target critic's step toward the critic after every critic step
    batch_size: int = 8192
    num_updates: int = 8
    policy_frequency: int = 4  # must divide num_updates: the actor steps num_updates / policy_frequency times a step
    buffer_size: int = 1024
    learning_starts: int = 10  # env steps collected before the first update
    actor_lr: float = 3e-4
    critic_lr: float = 3e-4
    alpha_lr: float = 3e-4
    weight_decay: float = 0.001
    max_grad_norm: float = 0.0  # 0: no clipping
    # the entropy temperature starts at alpha_init and is learnt toward a target entropy of
    # -target_entropy_ratio * num_actions (FastSAC: 0, a nearly deterministic policy; SAC's paper: 1)
    alpha_init: float = 0.001
    target_entropy_ratio: float = 0.0
    log_std_min: float = -5.0
    log_std_max: float = 0.0
    # bf16 autocast of the networks' forward and backward on CUDA (the weights and the optimisers stay float32)
    amp: bool = True
    tf32: bool = True
    reward_scale: float = 1.0
    normalize_obs: bool = True
    obs_clip: float = 10.0
    # goal-conditioned envs (agents.sac.relabel): the share of sampled transitions whose goal is replaced by one the
    # episode reached later (hindsight experience replay's "future" strategy)
    relabel_fraction: float = 0.8
    steps_per_iteration: int = 8

    seed: int = 0
    eval_gap: float = 30.0
    eval_envs: int = 64
    save_gap: int = 50
    keep_checkpoints: bool = False
    save_at: tuple[float, ...] = ()
    target: str = ""

    def validated(self) -> SACConfig:
        if self.agent != "AgentSAC":
            raise ValueError(f"agent={self.agent!r}: SACConfig is the config of 'AgentSAC'")
        check_positive_ints(self, ("num_critics", "num_atoms", "n_step", "batch_size", "num_updates",
                                   "policy_frequency", "buffer_size", "learning_starts", "steps_per_iteration"))
        if self.num_atoms < 2:
            raise ValueError(f"num_atoms={self.num_atoms}: a distribution needs at least 2 atoms, e.g. num_atoms=101")
        if self.num_updates % self.policy_frequency:
            raise ValueError(f"policy_frequency={self.policy_frequency} does not divide num_updates={self.num_updates}: "
                             "the actor steps once every policy_frequency critic steps of each env step; pick a divisor")
        if self.buffer_size <= self.n_step:
            raise ValueError(f"buffer_size={self.buffer_size} must exceed n_step={self.n_step}")
        for name in ("actor_dims", "critic_dims"):
            dims = getattr(self, name)
            if not dims or any(isinstance(d, bool) or not isinstance(d, int) or d < 1 for d in dims):
                raise ValueError(f"{name}={dims!r} must be a non-empty sequence of positive layer widths")
            setattr(self, name, tuple(dims))
        if not (_is_number(self.v_min) and _is_number(self.v_max) and self.v_min < self.v_max):
            raise ValueError(f"v_min={self.v_min!r}, v_max={self.v_max!r}: the critic's support needs v_min < v_max "
                             "covering the discounted returns, e.g. v_min=-20 v_max=20")
        for name in ("gamma", "tau"):
            v = getattr(self, name)
            if not (_is_number(v) and 0 < v <= 1):
                raise ValueError(f"{name}={v!r} must be a number in (0, 1], e.g. {name}={getattr(SACConfig, name)}")
        if not (_is_number(self.relabel_fraction) and 0 <= self.relabel_fraction <= 1):
            raise ValueError(f"relabel_fraction={self.relabel_fraction!r} must be a number in [0, 1], e.g. 0.8")
        for name in ("actor_lr", "critic_lr", "alpha_lr", "alpha_init", "reward_scale", "obs_clip"):
            v = getattr(self, name)
            if not (_is_number(v) and v > 0):
                raise ValueError(f"{name}={v!r} must be a positive number, e.g. {name}={getattr(SACConfig, name)}")
        for name in ("weight_decay", "max_grad_norm", "target_entropy_ratio"):
            v = getattr(self, name)
            if not (_is_number(v) and v >= 0):
                raise ValueError(f"{name}={v!r} must be 0 or a positive number, e.g. {name}={getattr(SACConfig, name)}")
        if not (_is_number(self.log_std_min) and _is_number(self.log_std_max) and self.log_std_min < self.log_std_max):
            raise ValueError(f"log_std_min={self.log_std_min!r}, log_std_max={self.log_std_max!r}: need "
                             "log_std_min < log_std_max, e.g. -5 and 0")
        for name in ("layer_norm", "amp"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name}={getattr(self, name)!r} must be True or False")
        self.check_run_fields()
        return self
