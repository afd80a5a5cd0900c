"""The PPO update: clipped surrogate, clipped value loss, entropy and action-bound terms, gradient
clipping, mini-epochs over shuffled mini-batches, and a learning rate adapted to a KL target.

With ``Config.overlap`` each rollout was drawn by the weights of one update earlier. The update then
uses the decoupled objective of Hilton et al. (2021, "Batch size-invariance for policy optimization"):
the clip and the KL that steers the learning rate are taken against the proximal policy (the weights at
the start of this update), and each sample's term is weighted by proximal over behaviour probability.
Clipped against the behaviour policy instead, the lag counts as KL of its own, holding the learning rate
down (docs/history.md, "Overlapped update").
Without a lag the proximal policy is the behaviour policy and the weight is exactly 1.

The learning rate lives in a device tensor that the optimizer reads, so adapting it per mini-batch
never waits on the host; losses are summed on the device. On CUDA one mini-batch step (forward,
backward, clipping, Adam, KL and learning-rate update) is captured once as a CUDA graph and replayed:
the step is a few hundred small kernels, and launching them one by one from Python costs more than
running them.
"""

from __future__ import annotations

import math

import torch

from agents import data_parallel
from agents.actor_critic import ActorCritic, gaussian_kl, gaussian_log_prob
from agents.config import Config
from agents.distributed import Workers
from agents.storage import RolloutStorage

LR_MIN, LR_MAX = 1e-5, 1e-2
ACTION_BOUND = 1.1  # the env clips to [-1, 1]; a mean far outside it only wastes gradient
# A sample the behaviour policy drew with a tiny probability gets a huge weight; with one update of lag
# almost all weights lie well below 2, so the bound trims only that rare tail's variance
MAX_BEHAVIOUR_WEIGHT = 2.0

# What an update reports of its mini-batch steps, by name: each step's loss terms, KL and learning rate averaged
# (the log's key for each), and the largest KL and rate of any step: the rule moves the rate 1.5x a mini-batch, and
# the rate after the last one alone (policy/lr) can read the floor after swinging to the ceiling
SUMMED = {"surrogate": "loss/surrogate", "value": "loss/value", "entropy": "loss/entropy", "kl": "policy/kl",
          "bounds": "loss/bounds", "lr": "policy/lr_mean"}
PEAKED = {"kl": "policy/kl_max", "lr": "policy/lr_max"}


def surrogate_loss(log_prob, old_log_prob, advantages, clip: float, behaviour_log_prob=None) -> torch.Tensor:
    """PPO's clipped surrogate of the ratio to ``old_log_prob``; with ``behaviour_log_prob`` (the policy
    that drew the actions, when it is not the old one) each term is weighted by old over behaviour."""
    ratio = torch.exp(log_prob - old_log_prob)
    terms = torch.min(ratio * advantages, ratio.clamp(1.0 - clip, 1.0 + clip) * advantages)
    if behaviour_log_prob is not None:
        terms = terms * torch.exp(old_log_prob - behaviour_log_prob).clamp(max=MAX_BEHAVIOUR_WEIGHT)
    return -terms.mean()


def value_loss(values, old_values, returns, clip: float) -> torch.Tensor:
    if clip <= 0:
        return (values - returns).pow(2).mean()
    clipped = old_values + (values - old_values).clamp(-clip, clip)
    return torch.max((values - returns).pow(2), (clipped - returns).pow(2)).mean()


def bounds_loss(mean: torch.Tensor) -> torch.Tensor:
    over = (mean - ACTION_BOUND).clamp(min=0) ** 2 + (-ACTION_BOUND - mean).clamp(min=0) ** 2
    return over.sum(-1).mean()


def adapted_lr(lr: torch.Tensor, kl: torch.Tensor, desired_kl: float) -> torch.Tensor:
    lower = torch.clamp(lr / 1.5, min=LR_MIN)
    higher = torch.clamp(lr * 1.5, max=LR_MAX)
    return torch.where(kl > 2.0 * desired_kl, lower, torch.where(kl < 0.5 * desired_kl, higher, lr))


def compiled(fn, device: torch.device, backend: str):
    """``fn`` under torch.compile; on CUDA, Inductor writes Triton kernels, so Triton must be importable."""
    if backend == "inductor" and device.type == "cuda":
        try:
            import triton  # noqa: F401, PLC0415
        except ImportError as e:
            raise RuntimeError(f"compile_update=True on {device} needs Triton ({e}): install the triton wheel "
                               "that matches this torch, or train without --compile-update") from None
    return torch.compile(fn, backend=backend, dynamic=False)


class PPO:
    def __init__(self, policy: ActorCritic, cfg: Config, device: torch.device, cuda_graph: bool = True,
                 workers: Workers | None = None, compile_backend: str = "inductor"):
        self.policy = policy
        self.workers = workers or Workers()
        self.cfg = cfg
        self.device = device
        # the KL target of this run's processes (grow-kl widens it with their number)
        self.desired_kl = data_parallel.kl_target(cfg.multi_gpu, cfg.desired_kl, self.workers.size)
        self.lr = torch.tensor(cfg.learning_rate, dtype=torch.float32, device=device)
        # the rate the KL rule adapts (or the fixed one) and Config.anneal_lr's decay factor (1 without it),
        # which the runner sets before each update; the captured step reads both by address, lr = their product
        self.lr_free = self.lr.clone()
        self.lr_scale = torch.ones((), dtype=torch.float32, device=device)
        is_cuda = device.type == "cuda"
        self.optimizer = torch.optim.Adam(policy.parameters(), lr=self.lr, fused=True, capturable=is_cuda)
        # Across several processes the captured step holds its NCCL all-reduce (tests/test_cuda.py
        # checks it against the eager step on 2 GPUs).
        self.use_graph = cuda_graph and is_cuda
        # Compiled, the loss's forward and backward are a few dozen fused Triton kernels instead of a few
        # hundred small ones; the optimiser, the collective and the clipping stay eager (and captured).
        self._loss_fn = compiled(self._losses, device, compile_backend) if cfg.compile_update else self._losses
        self._graph = None
        self._batch: dict[str, torch.Tensor] | None = None
        self._lagged = False

    def _bind(self, storage: RolloutStorage, size: int, lagged: bool) -> None:
        """Persistent inputs of the mini-batch step; a captured graph reads them by address."""
        self._batch = b = {
            "obs": storage.obs.flatten(0, 1), "actions": storage.actions.flatten(0, 1),
            "log_probs": storage.log_probs.flatten(0, 1), "values": storage.values.flatten(0, 1),
            "means": storage.means.flatten(0, 1), "returns": storage.returns.flatten(0, 1),
            "adv": torch.zeros_like(storage.advantages.flatten(0, 1)),
        }
        if getattr(storage, "critic_obs", None) is not None:  # an asymmetric actor-critic
            b["critic_obs"] = storage.critic_obs.flatten(0, 1)
        # the proximal policy: the behaviour policy's own buffers, unless the rollout lags an update
        b["prox_log_probs"] = torch.empty_like(b["log_probs"]) if lagged else b["log_probs"]
        b["prox_means"] = torch.empty_like(b["means"]) if lagged else b["means"]
        self._lagged = lagged
        self._idx = torch.zeros(size, dtype=torch.long, device=self.device)
        self._old_log_std = torch.zeros_like(self.policy.log_std)
        self._prox_log_std = torch.zeros_like(self.policy.log_std)
        self._sums = torch.zeros(len(SUMMED), device=self.device)  # in SUMMED's order
        self._peaks = torch.zeros(len(PEAKED), device=self.device)  # in PEAKED's order
        self._storage_id = id(storage)
        self._graph = None

    def _losses(self, idx: torch.Tensor) -> tuple[torch.Tensor, dict[str, torch.Tensor]]:
        """The mini-batch ``idx``'s loss, and its terms by name (detached): surrogate, value, entropy, kl, bounds."""
        cfg, policy, b = self.cfg, self.policy, self._batch
        critic = b["critic_obs"][idx] if "critic_obs" in b else None
        log_prob, entropy, values, mean = policy.evaluate(b["obs"][idx], b["actions"][idx], critic)
        kl = gaussian_kl(b["prox_means"][idx], self._prox_log_std, mean, policy.log_std).mean().detach()
        surr = surrogate_loss(log_prob, b["prox_log_probs"][idx], b["adv"][idx], cfg.clip_ratio,
                              b["log_probs"][idx] if self._lagged else None)
        v_loss = value_loss(values, b["values"][idx], b["returns"][idx], cfg.value_clip)
        ent = entropy.mean()
        b_loss = bounds_loss(mean)
        loss = surr + cfg.value_coef * v_loss - cfg.entropy_coef * ent + cfg.bounds_coef * b_loss
        terms = {"surrogate": surr, "value": v_loss, "entropy": ent, "kl": kl, "bounds": b_loss}
        return loss, {name: value.detach() for name, value in terms.items()}

    def _step(self) -> None:
        cfg, policy = self.cfg, self.policy
        loss, terms = self._loss_fn(self._idx)
        self.optimizer.zero_grad(set_to_none=False)
        loss.backward()
        # one collective per mini-batch: every process's gradients and KL, averaged
        (kl,) = self.workers.mean_grads_(policy.parameters(), terms["kl"])
        if self.desired_kl > 0:
            self.lr_free.copy_(adapted_lr(self.lr_free, kl, self.desired_kl))
        self.lr.copy_(self.lr_free * self.lr_scale)
        torch.nn.utils.clip_grad_norm_(policy.parameters(), cfg.max_grad_norm, foreach=True)
        self.optimizer.step()
        if cfg.max_noise_std > 0:  # in place: the captured step holds the parameter's address
            with torch.no_grad():
                policy.log_std.clamp_(max=math.log(cfg.max_noise_std))
        step = {**terms, "kl": kl, "lr": self.lr}
        self._sums += torch.stack([step[name] for name in SUMMED])
        torch.maximum(self._peaks, torch.stack([step[name] for name in PEAKED]), out=self._peaks)

    def release_graph(self) -> None:
        """Free the captured step. Under NCCL a communicator cannot be destroyed while a graph that
        holds one of its collectives lives: destroy_process_group would wait for ever."""
        self._graph = None

    def _capture(self) -> None:
        graph = torch.cuda.CUDAGraph()
        # thread_local: the NCCL watchdog thread queries events while this thread captures
        with torch.cuda.graph(graph, capture_error_mode="thread_local"):
            self._step()
        self._graph = graph

    def update(self, storage: RolloutStorage, old_log_std: torch.Tensor, num_minibatches: int,
               lagged: bool = False) -> dict:
        """PPO on ``storage``, drawn with noise ``old_log_std``; ``lagged``: by weights older than the
        policy's (Config.overlap), so the clip and the KL are taken against the policy as it is now."""
        cfg = self.cfg
        total = storage.obs.shape[0] * storage.obs.shape[1]
        size = total // num_minibatches
        if (self._batch is None or self._storage_id != id(storage) or self._idx.shape[0] != size
                or self._lagged != lagged):
            self._bind(storage, size, lagged)
        b = self._batch
        adv = storage.advantages.flatten(0, 1)
        b["adv"].copy_((adv - adv.mean()) / (adv.std() + 1e-8))
        self._old_log_std.copy_(old_log_std)
        if lagged:  # one forward pass of the actor over the rollout, outside the captured step
            with torch.no_grad():
                b["prox_means"].copy_(self.policy.actor(b["obs"]))
                b["prox_log_probs"].copy_(gaussian_log_prob(b["actions"], b["prox_means"], self.policy.log_std))
                self._prox_log_std.copy_(self.policy.log_std)
        else:
            self._prox_log_std.copy_(old_log_std)
        self._sums.zero_()
        self._peaks.zero_()

        def epoch() -> None:
            perm = torch.randperm(total, device=self.device)
            for i in range(num_minibatches):
                self._idx.copy_(perm[i * size : (i + 1) * size])
                if self._graph is not None:
                    self._graph.replay()
                else:
                    self._step()

        for e in range(cfg.repeat_times):
            if self.use_graph and self._graph is None:
                # The first pass runs eagerly on a side stream (CUDA graphs want warmed-up kernels
                # and existing Adam state); then the step is captured for every later mini-batch.
                main, side = torch.cuda.current_stream(self.device), torch.cuda.Stream(self.device)
                side.wait_stream(main)
                with torch.cuda.stream(side):
                    epoch()
                main.wait_stream(side)
                self._capture()
            else:
                epoch()
        self._sums /= cfg.repeat_times * num_minibatches
        return {**{key: self._sums[i].clone() for i, key in enumerate(SUMMED.values())},
                **{key: self._peaks[i].clone() for i, key in enumerate(PEAKED.values())},
                "policy/lr": self.lr.clone(), "policy/noise_std": self.policy.log_std.detach().exp().mean()}
