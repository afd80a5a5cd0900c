"""Episode statistics of a rollout, kept on the device and reduced once per iteration."""

from __future__ import annotations

import torch


class EpisodeTracker:
    """Return, length and mean forward speed of the episodes that finish during rollouts.

    Envs that report ``info["episode"]`` (return ``r``, length ``l``, speed ``s``) cost one copy per
    step; for others the tracker sums rewards itself.
    """

    SUMS = 5  # the length of take()'s vector

    def __init__(self, horizon: int, num_envs: int, device: torch.device):
        self.ended = torch.zeros(horizon, 3, num_envs, device=device)  # r, l, s of episodes ending at t
        self.has_speed = False
        self.ret = torch.zeros(num_envs, device=device)
        self.length = torch.zeros(num_envs, device=device)
        # since the last read: episodes, sum of returns, lengths, speeds, episodes with a speed
        self.sums = torch.zeros(5, dtype=torch.float64, device=device)

    def record(self, t: torch.Tensor, reward: torch.Tensor, done: torch.Tensor, info: dict) -> None:
        """The episodes ending at step ``t`` (a one-element index tensor on the device) of the rollout."""
        ep = info.get("episode") if isinstance(info, dict) else None
        if ep is not None and "r" in ep and "l" in ep:
            self.has_speed = "s" in ep
            speed = ep["s"] if self.has_speed else torch.zeros_like(ep["r"])
            self.ended.index_copy_(0, t, torch.stack([ep["r"], ep["l"].float(), speed])[None])
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
        self.sums += torch.cat([count[None], totals, speed_count[None]]).double()

    def take(self, workers=None) -> torch.Tensor:
        """The sums since the last call, as a new device tensor, and restart them (no host read).

        With ``workers``, the episodes of every process count."""
        if workers is not None:
            workers.sum_(self.sums)
        taken = self.sums.clone()
        self.sums.zero_()
        return taken

    @staticmethod
    def summary(sums: list[float]) -> dict:
        """Means of the episodes in ``take()``'s sums, read to the host (None where there were none)."""
        n, r, length, s, ns = sums
        return {
            "episodes": int(n),
            "return": r / n if n else None,
            "length": length / n if n else None,
            "speed": s / ns if ns else None,
        }

    def read_and_clear(self, workers=None) -> dict:
        """One host read: means of the episodes finished since the last call."""
        return self.summary(self.take(workers).tolist())
