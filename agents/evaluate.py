"""Deterministic-policy evaluation: each env plays one episode with the action mean."""

from __future__ import annotations

import torch

from agents.rollout import extra_keys


def reward_terms(info: dict, n: int) -> list[str]:
    """The per-step reward terms an env reports in ``info`` (agents.protocol: Gymnasium's ``reward_*``
    keys, and ``*_penalty``), each a tensor of one value per env."""
    return [k for k, v in info.items() if (k.startswith("reward_") or k.endswith("_penalty"))
            and isinstance(v, torch.Tensor) and v.shape == (n,)]


class EpisodeTally:
    """The first episode of every env, summed step by step on the device: return, length, forward speed and
    each reward term. Every update is in place and the step count lives on the device, so that one captured
    step (agents.background_eval) replays as any of them; steps after ``max_steps`` count for nothing."""

    def __init__(self, n: int, max_steps: int, device: torch.device):
        self.n, self.max_steps = n, max_steps
        self.t = torch.zeros((), dtype=torch.long, device=device)  # steps taken
        self.finished = torch.zeros(n, dtype=torch.bool, device=device)
        self.ret, self.length = torch.zeros(n, device=device), torch.zeros(n, device=device)
        self.out_ret, self.out_len = torch.zeros(n, device=device), torch.zeros(n, device=device)
        self.out_speed = torch.zeros(n, device=device)
        self.names: list[str] | None = None  # the env's reward terms, known at its first step
        self.terms = torch.zeros(0, n, device=device)
        self.extra: list[str] = []  # the env's further per-episode statistics (agents.protocol), at its end
        self.out_extra = torch.zeros(0, n, device=device)

    def reset(self) -> None:
        for t in (self.t, self.finished, self.ret, self.length, self.out_ret, self.out_len, self.out_speed, self.terms,
                  self.out_extra):
            t.zero_()

    def add(self, reward: torch.Tensor, terminated: torch.Tensor, truncated: torch.Tensor, info: dict) -> None:
        if self.names is None:
            self.names = reward_terms(info, self.n)
            self.terms = torch.zeros(len(self.names), self.n, device=self.ret.device)
            self.extra = extra_keys(info.get("episode", {}))
            self.out_extra = torch.zeros(len(self.extra), self.n, device=self.ret.device)
        live = ~self.finished & (self.t < self.max_steps)
        self.ret.add_(reward * live)
        if self.names:  # an episode's terms stop with it, as its return does
            self.terms.add_(torch.stack([info[k] for k in self.names]) * live)
        self.length.add_(live.float())
        ended = (terminated | truncated) & live
        torch.where(ended, self.ret, self.out_ret, out=self.out_ret)
        torch.where(ended, self.length, self.out_len, out=self.out_len)
        if self.extra:
            stats = torch.stack([info["episode"][k].float() for k in self.extra])
            torch.where(ended, stats, self.out_extra, out=self.out_extra)
        speed = info.get("episode", {}).get("s")
        if speed is not None:
            torch.where(ended, speed, self.out_speed, out=self.out_speed)
        # an episode still running at the last step counted keeps its speed so far (0 if the env reports none)
        so_far = info.get("episode_so_far", {}).get("s")
        if so_far is not None:
            torch.where(live & ~ended & (self.t == self.max_steps - 1), so_far, self.out_speed, out=self.out_speed)
        self.finished.logical_or_(ended)
        self.t.add_(1)

    def means(self) -> torch.Tensor:
        """Return, length, speed, each term and each further statistic, averaged over the envs, as one device tensor
        (no host read); an episode still running at ``max_steps`` counts with what it has so far, and with 0 for the
        statistics an env reports at an episode's end."""
        ret = torch.where(self.finished, self.out_ret, self.ret)
        length = torch.where(self.finished, self.out_len, self.length)
        return torch.cat([torch.stack([ret.mean(), length.mean(), self.out_speed.mean()]), self.terms.mean(dim=1),
                          self.out_extra.mean(dim=1)])

    def row(self, means: list[float]) -> dict:
        """``means()`` read to the host, as the row's ``eval/...`` entries."""
        r, ln, s = means[:3]
        k = 3 + len(self.names or [])
        return {"eval/return": r, "eval/length": ln, "eval/speed": s,
                **{f"eval/{name}": v for name, v in zip(self.names or [], means[3:k])},
                **{f"eval/{name}": v for name, v in zip(self.extra, means[k:])}}


@torch.no_grad()
def evaluate(env, policy, normalize, max_steps: int, recorder=None) -> dict:
    """Mean return, length and forward speed of the first episode of every env (one host read), and
    the mean episode sum of each reward term the env reports (``eval/reward_forward``, ...).

    Forward speeds are the env's own (``info["episode"]["s"]``, agents.protocol): nothing here computes
    one. An episode still running after ``max_steps`` counts with what it has so far, its speed from
    ``info["episode_so_far"]["s"]`` (0 if the env reports none). A ``recorder`` (agents.protocol) sees
    the env after the reset and after every step."""
    obs, _ = env.reset()
    if recorder is not None:
        recorder.capture(env)
    tally = EpisodeTally(env.num_envs, max_steps, obs.device)
    for _ in range(max_steps):
        obs, reward, terminated, truncated, info = env.step(policy.act_deterministic(normalize(obs)))
        if recorder is not None:
            recorder.capture(env)
        tally.add(reward, terminated, truncated, info)
    return tally.row(tally.means().tolist())
