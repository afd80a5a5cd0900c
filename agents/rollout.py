"""Episode statistics of a rollout, kept on the device and reduced once per iteration."""

from __future__ import annotations

import torch

CORE = ("r", "l", "s")  # return, length, forward speed


def extra_keys(episode: dict) -> list[str]:
    """The per-episode statistics an env reports beside return, length and speed (agents.protocol): a tracking
    error, say. Masks (``_r``) and non-tensors are not statistics."""
    return sorted(k for k, v in episode.items()
                  if k not in CORE and not k.startswith("_") and isinstance(v, torch.Tensor) and v.dim() == 1)


class EpisodeTracker:
    """Return, length, mean forward speed and the env's further statistics (``extra``) of the episodes that finish
    during rollouts.

    Envs that report ``info["episode"]`` (return ``r``, length ``l``, speed ``s``, and more) cost one copy per
    step; for others the tracker sums rewards itself. Which statistics an env reports is learnt at its first
    step, which the runner always takes eagerly, before any capture.
    """

    def __init__(self, horizon: int, num_envs: int, device: torch.device):
        self.horizon, self.num_envs, self.device = horizon, num_envs, device
        self.extra: list[str] = []
        self.ended = torch.zeros(horizon, 3, num_envs, device=device)  # r, l, s (and extras) of episodes ending at t
        self.has_speed = False
        self.ret = torch.zeros(num_envs, device=device)
        self.length = torch.zeros(num_envs, device=device)
        # since the last read: episodes, sum of returns, lengths, speeds, episodes with a speed, then each extra's sum
        self.sums = torch.zeros(5, dtype=torch.float64, device=device)
        self._learnt = False

    @property
    def size(self) -> int:
        """The length of take()'s vector."""
        return 5 + len(self.extra)

    def _learn(self, episode: dict | None) -> None:
        self._learnt = True
        if episode is not None and "r" in episode and "l" in episode:
            self.extra = extra_keys(episode)
            if self.extra:
                self.ended = torch.zeros(self.horizon, 3 + len(self.extra), self.num_envs, device=self.device)
                self.sums = torch.zeros(5 + len(self.extra), dtype=torch.float64, device=self.device)

    def record(self, t: torch.Tensor, reward: torch.Tensor, done: torch.Tensor, info: dict) -> None:
        """The episodes ending at step ``t`` (a one-element index tensor on the device) of the rollout."""
        ep = info.get("episode") if isinstance(info, dict) else None
        if not self._learnt:
            self._learn(ep)
        if ep is not None and "r" in ep and "l" in ep:
            self.has_speed = "s" in ep
            speed = ep["s"] if self.has_speed else torch.zeros_like(ep["r"])
            rows = [ep["r"], ep["l"].float(), speed, *(ep[k].float() for k in self.extra)]
            self.ended.index_copy_(0, t, torch.stack(rows)[None])
            return
        self.ret += reward
        self.length += 1
        self.ended.index_copy_(0, t, torch.stack([self.ret, self.length, torch.zeros_like(self.ret)])[None])
        keep = 1.0 - done.float()
        self.ret *= keep
        self.length *= keep

    def end_rollout(self, dones: torch.Tensor) -> None:
        """Fold the rollout's finished episodes (``dones``: (T, N), 1 where one ended) into the sums."""
        count = dones.sum()
        totals = (self.ended * dones.unsqueeze(1)).sum((0, 2))
        speed_count = count if self.has_speed else torch.zeros_like(count)
        self.sums += torch.cat([count[None], totals[:3], speed_count[None], totals[3:]]).double()

    def take(self, workers=None) -> torch.Tensor:
        """The sums since the last call, as a new device tensor, and restart them (no host read).

        With ``workers``, the episodes of every process count."""
        if workers is not None:
            workers.sum_(self.sums)
        taken = self.sums.clone()
        self.sums.zero_()
        return taken

    def summary(self, sums: list[float]) -> dict:
        """Means of the episodes in ``take()``'s sums, read to the host (None where there were none); each extra
        statistic as ``episode/<key>``."""
        n, r, length, s, ns = sums[:5]
        out = {
            "episodes": int(n),
            "return": r / n if n else None,
            "length": length / n if n else None,
            "speed": s / ns if ns else None,
        }
        out.update({f"episode/{k}": (v / n if n else None) for k, v in zip(self.extra, sums[5:])})
        return out

    def read_and_clear(self, workers=None) -> dict:
        """One host read: means of the episodes finished since the last call."""
        return self.summary(self.take(workers).tolist())
