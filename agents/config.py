"""Training configuration, named after ElegantRL's ``Arguments`` (the ElegantRL tutorial this project
started from) where the idea matches.

Units: ``horizon_len`` is env steps per env per iteration (the ElegantRL tutorial's ``target_step``);
``minibatch_size`` is the mini-batch size in samples (CleanRL's name; its ``batch_size`` is the whole
rollout, and older runs' configs wrote ``batch_size``: ``RENAMED``); ``repeat_times`` is the
number of passes over each rollout; ``eval_gap`` is wall-clock seconds between evaluations; ``save_gap`` is iterations
between checkpoints.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields, replace
from typing import Callable

from agents import data_parallel

# Fields renamed since configs and checkpoints were first saved: the old name is still read (Config.renamed)
RENAMED = {"batch_size": "minibatch_size"}


def _is_number(v) -> bool:
    """A finite int or float (True and False are not numbers here)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def check_positive_ints(cfg, names: tuple[str, ...]) -> None:
    """Each of ``cfg``'s fields ``names`` a positive integer (True and False are not), or a ValueError naming the
    field, its value and its default."""
    for name in names:
        v = getattr(cfg, name)
        if isinstance(v, bool) or not isinstance(v, int) or v < 1:
            raise ValueError(f"{name}={v!r} must be a positive integer, e.g. {name}={getattr(type(cfg), name)}")


class RunConfig:
    """What every learner's configuration does alike: presets with overrides, checked replacements, the target, the
    dict a run directory's config.json and a checkpoint keep. ``RENAMED``: fields under an earlier name."""

    RENAMED: dict[str, str] = {}

    @classmethod
    def renamed(cls, values: dict) -> dict:
        """``values`` with fields under an earlier name (``RENAMED``) under today's; both given: today's wins."""
        out = dict(values)
        for old, new in cls.RENAMED.items():
            if old in out:
                value = out.pop(old)
                out.setdefault(new, value)
        return out

    @classmethod
    def from_preset(cls, preset: dict, **overrides):
        """A task's starting point (the env's side keeps its tasks' presets: warpgym's registry entry) with
        ``overrides``, checked."""
        return cls(**{**dict(preset), **cls.renamed(overrides)}).validated()

    def replace(self, **changes):
        changes = self.renamed(changes)
        names = {f.name for f in fields(self)}
        unknown = sorted(set(changes) - names)
        if unknown:
            raise ValueError(f"unknown config field(s) {unknown}: choose from {sorted(names)}")
        return replace(self, **changes).validated()

    def validated(self):
        raise NotImplementedError

    def check_run_fields(self) -> None:
        """The fields of the run itself (evaluations, checkpoints, the target), as every learner has them."""
        check_positive_ints(self, ("save_gap", "eval_envs"))
        if not (_is_number(self.eval_gap) and self.eval_gap >= 0):
            raise ValueError(f"eval_gap={self.eval_gap!r} must be 0 or a positive number of seconds")
        for name in ("normalize_obs", "tf32", "keep_checkpoints"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name}={getattr(self, name)!r} must be True or False")
        self.target_pair()
        marks = tuple(self.save_at)
        if any(not (isinstance(t, (int, float)) and math.isfinite(t) and t >= 0) for t in marks):
            raise ValueError(f"save_at={self.save_at!r} must hold non-negative numbers of seconds, e.g. (60, 120)")
        self.save_at = tuple(sorted(float(t) for t in marks))

    def target_pair(self) -> tuple[str, float] | None:
        """``target`` as (key, value), or None without one; raises on a malformed one."""
        if not self.target:
            return None
        key, sep, value = str(self.target).partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not (sep and key.strip() and math.isfinite(number)):
            raise ValueError(f"target={self.target!r}: write KEY=VALUE with a logged key and a number, "
                             "e.g. target=eval/speed=9.5 or target=eval/return=5850")
        return key.strip(), number

    def to_dict(self) -> dict:
        d = asdict(self)
        for key in ("env_class", "eval_env_class"):
            d[key] = getattr(d[key], "__qualname__", None) if d[key] is not None else None
        return d


@dataclass
class Config(RunConfig):
    RENAMED = RENAMED

    # mirrors ElegantRL's ``Arguments.agent`` for the tutorial's workflow; PPO is the one agent here
    agent: str = "AgentPPO"
    env_class: Callable | None = None  # builds the training env from env_args
    env_args: dict = field(default_factory=dict)
    eval_env_class: Callable | None = None
    eval_env_args: dict = field(default_factory=dict)

    net_dims: tuple[int, ...] = (256, 128, 64)
    activation: str = "elu"
    init_noise_std: float = 1.0
    minibatch_size: int = 32768  # samples per mini-batch step (rsl_rl gives num_mini_batches instead)
    horizon_len: int = 16
    repeat_times: int = 4
    learning_rate: float = 3e-4
    gamma: float = 0.99
    lambda_gae: float = 0.95
    clip_ratio: float = 0.2
    value_clip: float = 0.2
    value_coef: float = 1.0
    entropy_coef: float = 0.0
    # the noise's std is held at or under this after every optimiser step (0: unbounded; skrl's max_log_std as a
    # std): an entropy bonus can push it past the actions' range, where the env clips most samples (Swimmer-v5's
    # seed 3 at entropy_coef=0.01: 3.7, docs/benchmarks.md)
    max_noise_std: float = 0.0
    bounds_coef: float = 1e-4  # keeps the action mean near [-1, 1], where the env clips
    max_grad_norm: float = 1.0
    desired_kl: float = 0.008  # 0 disables the adaptive learning rate
    # the learning rate (with desired_kl, the one the KL rule picks) times 1 - progress through the run's
    # budget (its time limit, samples or iterations, whichever ends first): SB3's and CleanRL's linear decay
    anneal_lr: bool = False
    reward_scale: float = 1.0
    normalize_obs: bool = True
    # observations (every env's steps, all processes together) after which the normaliser's statistics stay
    # as they are (rsl_rl's EmpiricalNormalization ``until``); 0: it learns throughout. A running mean of an
    # input the policy steers follows the policy (a cart's position: docs/benchmarks.md, InvertedPendulum-v5)
    normalize_until: float = 0
    tf32: bool = True  # on CUDA, let matmuls use TF32 tensor cores
    # collect the next rollout while PPO learns from the last one, on two CUDA streams, each rollout
    # learnt one update after the weights that collected it (agents.overlap)
    overlap: bool = False
    # torch.compile the PPO mini-batch loss (forward and backward): fewer, fused kernels per step; the first
    # update compiles it, seconds of a start (docs/history.md, "Compiled update")
    compile_update: bool = False
    obs_clip: float = 5.0
    # how several processes (torchrun, one per GPU) divide the work: agents/data_parallel.py. "grow-kl": each
    # GPU steps num_envs envs and a mini-batch stays minibatch_size samples across them, so G GPUs make G times the
    # optimiser steps of one in an iteration about as long, under a KL target G times desired_kl
    multi_gpu: str = data_parallel.DEFAULT
    # stop once a logged value reaches a number, "KEY=VALUE" (e.g. "eval/speed=9.5", "eval/return=5850"): the
    # first row whose KEY is at least VALUE ends the run as its time limit would (rl_games' score_to_win)
    target: str = ""
    # start training with every env's elapsed steps drawn over its time limit (rsl_rl's init_at_random_ep_len, which
    # mjlab trains with), where the env offers it (agents.protocol's stagger_episodes)
    stagger_episodes: bool = False

    seed: int = 0
    eval_gap: float = 30.0
    eval_envs: int = 64
    # play each evaluation beside training, a frozen copy of the policy on a side CUDA stream, one step beside each
    # of the rollout's, instead of stopping the run for it (agents.background_eval); the run's last evaluation
    # stays synchronous
    eval_background: bool = False
    save_gap: int = 50
    keep_checkpoints: bool = False  # also keep checkpoint-<iteration>.pt at every save
    # wall-clock seconds since the run started at which to keep a checkpoint-<iteration>.pt (the first
    # iteration that ends after each), e.g. (60, 120): policies of known training time to compare
    save_at: tuple[float, ...] = ()

    def validated(self) -> Config:
        if self.agent != "AgentPPO":
            raise ValueError(f"agent={self.agent!r}: this package implements 'AgentPPO' only")
        check_positive_ints(self, ("minibatch_size", "horizon_len", "repeat_times"))
        if not self.net_dims or any((not isinstance(d, int)) or d < 1 for d in self.net_dims):
            raise ValueError(f"net_dims={self.net_dims!r} must be a non-empty sequence of positive layer widths")
        for name, lo, hi in (("gamma", 0.0, 1.0), ("lambda_gae", 0.0, 1.0), ("clip_ratio", 0.0, 1.0)):
            v = getattr(self, name)
            if not (_is_number(v) and lo < v <= hi):
                raise ValueError(f"{name}={v!r} must be a number in ({lo}, {hi}], e.g. {name}={getattr(Config, name)}")
        for name in ("learning_rate", "init_noise_std", "reward_scale", "max_grad_norm", "obs_clip"):
            v = getattr(self, name)
            if not (_is_number(v) and v > 0):
                raise ValueError(f"{name}={v!r} must be a positive number, e.g. {name}={getattr(Config, name)}")
        for name in ("value_clip", "value_coef", "entropy_coef", "bounds_coef", "desired_kl", "eval_gap",
                     "normalize_until", "max_noise_std"):
            v = getattr(self, name)
            if not (_is_number(v) and v >= 0):
                raise ValueError(f"{name}={v!r} must be 0 or a positive number, e.g. {name}={getattr(Config, name)}")
        for name in ("overlap", "compile_update", "anneal_lr", "eval_background", "stagger_episodes"):
            if not isinstance(getattr(self, name), bool):
                raise ValueError(f"{name}={getattr(self, name)!r} must be True or False")
        data_parallel.check_mode(self.multi_gpu)
        self.check_run_fields()
        if self.activation not in ("elu", "relu", "tanh"):
            raise ValueError(f"activation={self.activation!r}: choose 'elu', 'relu' or 'tanh'")
        self.net_dims = tuple(self.net_dims)
        return self

    def check_batch(self, num_envs: int, processes: int = 1) -> int:
        """Mini-batches per pass for this process's ``num_envs`` envs among ``processes`` (agents.data_parallel);
        raises if they do not divide evenly."""
        return data_parallel.minibatches(self.multi_gpu, num_envs, self.horizon_len, self.minibatch_size, processes)

    def process_horizon(self, processes: int = 1) -> int:
        """Steps one process collects per iteration among ``processes`` (``horizon_len`` but under
        ``multi_gpu='split-horizon'``, where it is the run's total: agents.data_parallel)."""
        return data_parallel.horizon_per_process(self.multi_gpu, self.horizon_len, processes)
