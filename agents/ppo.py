"""The PPO update: clipped surrogate, clipped value loss, entropy and action-bound terms, gradient
clipping, mini-epochs over shuffled mini-batches, and a learning rate adapted to a KL target.

The learning rate lives in a device tensor that the optimizer reads, so adapting it per mini-batch
never waits on the host. Losses are summed on the device and returned as tensors.
"""

from __future__ import annotations

import torch

from agents.actor_critic import ActorCritic, gaussian_kl
from agents.config import Config
from agents.storage import RolloutStorage

LR_MIN, LR_MAX = 1e-5, 1e-2
ACTION_BOUND = 1.1  # the env clips to [-1, 1]; a mean far outside it only wastes gradient


def surrogate_loss(log_prob, old_log_prob, advantages, clip: float) -> torch.Tensor:
    ratio = torch.exp(log_prob - old_log_prob)
    return -torch.min(ratio * advantages, ratio.clamp(1.0 - clip, 1.0 + clip) * advantages).mean()


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


class PPO:
    def __init__(self, policy: ActorCritic, cfg: Config, device: torch.device):
        self.policy = policy
        self.cfg = cfg
        self.lr = torch.tensor(cfg.learning_rate, dtype=torch.float32, device=device)
        self.optimizer = torch.optim.Adam(policy.parameters(), lr=self.lr, fused=True)

    def update(self, storage: RolloutStorage, old_log_std: torch.Tensor, num_minibatches: int) -> dict:
        cfg, policy = self.cfg, self.policy
        obs = storage.obs.flatten(0, 1)
        actions = storage.actions.flatten(0, 1)
        old_log_probs = storage.log_probs.flatten(0, 1)
        old_values = storage.values.flatten(0, 1)
        old_means = storage.means.flatten(0, 1)
        returns = storage.returns.flatten(0, 1)
        adv = storage.advantages.flatten(0, 1)
        adv = (adv - adv.mean()) / (adv.std() + 1e-8)

        total = obs.shape[0]
        size = total // num_minibatches
        dev = obs.device
        sums = torch.zeros(5, device=dev)  # surrogate, value, entropy, kl, bounds
        for _ in range(cfg.repeat_times):
            perm = torch.randperm(total, device=dev)
            for i in range(num_minibatches):
                idx = perm[i * size : (i + 1) * size]
                log_prob, entropy, values, mean = policy.evaluate(obs[idx], actions[idx])
                with torch.no_grad():
                    kl = gaussian_kl(old_means[idx], old_log_std, mean, policy.log_std).mean()
                    if cfg.desired_kl > 0:
                        self.lr.copy_(adapted_lr(self.lr, kl, cfg.desired_kl))
                surr = surrogate_loss(log_prob, old_log_probs[idx], adv[idx], cfg.clip_ratio)
                v_loss = value_loss(values, old_values[idx], returns[idx], cfg.value_clip)
                ent = entropy.mean()
                b_loss = bounds_loss(mean)
                loss = surr + cfg.value_coef * v_loss - cfg.entropy_coef * ent + cfg.bounds_coef * b_loss
                self.optimizer.zero_grad(set_to_none=True)
                loss.backward()
                torch.nn.utils.clip_grad_norm_(policy.parameters(), cfg.max_grad_norm, foreach=True)
                self.optimizer.step()
                sums += torch.stack([surr.detach(), v_loss.detach(), ent.detach(), kl, b_loss.detach()])
        sums /= cfg.repeat_times * num_minibatches
        return {"loss/surrogate": sums[0], "loss/value": sums[1], "loss/entropy": sums[2],
                "policy/kl": sums[3], "loss/bounds": sums[4], "policy/lr": self.lr.clone(),
                "policy/noise_std": policy.log_std.detach().exp().mean()}
