"""The soft actor-critic updates of one env step, everything on the device: ``num_updates`` critic steps on fresh
batches (clipped double Q on distributions: the target is the projected distribution of whichever target critic
values the next action lower), the actor and the entropy temperature every ``policy_frequency`` of them, the target
critic following the critic after every step. No step reads the host, so one env step's updates can be captured
as a CUDA graph and replayed."""

from __future__ import annotations

import copy
import math
from contextlib import contextmanager

import torch

from agents.sac.config import SACConfig
from agents.sac.networks import DistributionalCritic, SquashedGaussianPolicy, project
from agents.sac.relabel import GoalSpec, relabel
from agents.sac.replay import ReplayBuffer

# the statistics every iteration logs, as means over its steps (the actor's over the actor's steps)
CRITIC_STATS = ("sac/critic_loss", "sac/q_target")
ACTOR_STATS = ("sac/actor_loss", "sac/entropy", "sac/alpha", "sac/q_policy")


class SAC:
    def __init__(self, policy: SquashedGaussianPolicy, critic: DistributionalCritic, cfg: SACConfig,
                 buffer: ReplayBuffer, num_actions: int, device: torch.device, normalize, normalize_critic,
                 goals: GoalSpec | None = None):
        self.policy, self.critic, self.cfg, self.buffer, self.device = policy, critic, cfg, buffer, device
        self.normalize, self.normalize_critic, self.goals = normalize, normalize_critic, goals
        self.critic_target = copy.deepcopy(critic).requires_grad_(False)
        self.log_alpha = torch.nn.Parameter(torch.full((1,), math.log(cfg.alpha_init), device=device))
        self.target_entropy = -cfg.target_entropy_ratio * num_actions
        cuda = device.type == "cuda"
        # capturable: the optimisers' step counts stay on the device, so that a captured step replays them
        adam = dict(betas=(0.9, 0.95), fused=True, capturable=cuda)
        self.actor_opt = torch.optim.AdamW(policy.parameters(), lr=cfg.actor_lr, weight_decay=cfg.weight_decay, **adam)
        self.critic_opt = torch.optim.AdamW(critic.parameters(), lr=cfg.critic_lr, weight_decay=cfg.weight_decay,
                                            **adam)
        self.alpha_opt = torch.optim.AdamW([self.log_alpha], lr=cfg.alpha_lr, weight_decay=0.0, **adam)
        self.amp = cfg.amp and cuda
        # sums since the last take(): the critic's statistics, its steps, the actor's, its steps
        self.sums = torch.zeros(len(CRITIC_STATS) + 1 + len(ACTOR_STATS) + 1, device=device)
        self._one = torch.ones((), device=device)  # a step's count in the sums

    @contextmanager
    def _autocast(self):
        # no weight-cast cache: a captured graph must cast the weights every replay, after the optimiser's step
        with torch.autocast(device_type=self.device.type, dtype=torch.bfloat16, enabled=self.amp,
                            cache_enabled=False):
            yield

    def batch(self) -> dict[str, torch.Tensor]:
        """A sampled batch (relabelled for a goal-conditioned env), its observations normalised as the policy and
        the critic see them, its reward scaled."""
        cfg = self.cfg
        b = self.buffer.sample(cfg.batch_size, cfg.n_step, cfg.gamma)
        if self.goals is not None:
            relabel(b, self.buffer, self.goals, cfg.relabel_fraction)
        out = {"obs": self.normalize(b["obs"]), "next_obs": self.normalize(b["next_obs"]), "actions": b["actions"],
               "reward": b["reward"] * cfg.reward_scale, "discount": b["discount"]}
        if "critic_obs" in b:
            out["critic_obs"] = self.normalize_critic(b["critic_obs"])
            out["next_critic_obs"] = self.normalize_critic(b["next_critic_obs"])
        else:
            out["critic_obs"], out["next_critic_obs"] = out["obs"], out["next_obs"]
        return out

    def target_distribution(self, b: dict[str, torch.Tensor]) -> tuple[torch.Tensor, torch.Tensor]:
        """The soft Bellman target's distribution, (B, atoms), and its mean value over the batch."""
        with torch.no_grad():
            with self._autocast():
                next_actions, next_log_prob = self.policy.sample(b["next_obs"])
                logits = self.critic_target(b["next_critic_obs"], next_actions)
            probs = logits.float().softmax(-1)  # (critics, B, atoms)
            values = (probs * self.critic_target.support).sum(-1)
            lowest = values.argmin(0)  # clipped double Q, per sample
            chosen = probs.gather(0, lowest[None, :, None].expand(1, *probs.shape[1:])).squeeze(0)
            alpha = self.log_alpha.exp()
            reward = b["reward"] - b["discount"] * alpha * next_log_prob.float()
            target = project(chosen, reward, b["discount"], self.critic_target.support)
            return target, (target * self.critic_target.support).sum(-1).mean()

    def critic_step(self, b: dict[str, torch.Tensor]) -> None:
        target, q_target = self.target_distribution(b)
        with self._autocast():
            logits = self.critic(b["critic_obs"], b["actions"])
        # cross-entropy of each critic's distribution against the target, summed over the critics
        loss = -(target * logits.float().log_softmax(-1)).sum(-1).mean(-1).sum()
        self.critic_opt.zero_grad(set_to_none=False)
        loss.backward()
        if self.cfg.max_grad_norm > 0:
            torch.nn.utils.clip_grad_norm_(self.critic.parameters(), self.cfg.max_grad_norm, foreach=True)
        self.critic_opt.step()
        with torch.no_grad():
            for tp, p in zip(self.critic_target.parameters(), self.critic.parameters()):
                tp.lerp_(p, self.cfg.tau)
        n = len(CRITIC_STATS)
        self.sums[: n + 1] += torch.stack([loss.detach(), q_target, self._one])

    def actor_step(self, b: dict[str, torch.Tensor]) -> None:
        self.critic.requires_grad_(False)  # the actor's loss moves the actor alone
        try:
            with self._autocast():
                actions, log_prob = self.policy.sample(b["obs"])
                logits = self.critic(b["critic_obs"], actions)
            q = self.critic.values(logits).mean(0)  # the critics' mean: clipping here too biases the actor low
            log_prob = log_prob.float()
            alpha = self.log_alpha.exp().detach()
            loss = (alpha * log_prob - q).mean()
            self.actor_opt.zero_grad(set_to_none=False)
            loss.backward()
        finally:
            self.critic.requires_grad_(True)
        if self.cfg.max_grad_norm > 0:
            torch.nn.utils.clip_grad_norm_(self.policy.parameters(), self.cfg.max_grad_norm, foreach=True)
        self.actor_opt.step()
        alpha_loss = -(self.log_alpha.exp() * (log_prob.detach() + self.target_entropy)).mean()
        self.alpha_opt.zero_grad(set_to_none=False)
        alpha_loss.backward()
        self.alpha_opt.step()
        n = len(CRITIC_STATS) + 1
        self.sums[n:] += torch.stack([loss.detach(), -log_prob.detach().mean(), alpha[0], q.detach().mean(),
                                      self._one])

    def update(self) -> None:
        """One env step's updates."""
        for i in range(self.cfg.num_updates):
            b = self.batch()
            self.critic_step(b)
            if (i + 1) % self.cfg.policy_frequency == 0:
                self.actor_step(b)

    def take_stats(self) -> dict[str, torch.Tensor]:
        """Means of the statistics since the last call, as device tensors (no host read); zeros before any update."""
        s = self.sums.clone()
        self.sums.zero_()
        n = len(CRITIC_STATS)
        critic = s[:n] / s[n].clamp(min=1)
        actor = s[n + 1 : -1] / s[-1].clamp(min=1)
        return {**dict(zip(CRITIC_STATS, critic)), **dict(zip(ACTOR_STATS, actor))}

    def optimizer_states(self) -> dict:
        return {"actor": self.actor_opt.state_dict(), "critic": self.critic_opt.state_dict(),
                "alpha": self.alpha_opt.state_dict()}

    def load_optimizer_states(self, states: dict) -> None:
        self.actor_opt.load_state_dict(states["actor"])
        self.critic_opt.load_state_dict(states["critic"])
        self.alpha_opt.load_state_dict(states["alpha"])
