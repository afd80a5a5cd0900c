"""Running episode statistics kept on the device, so a rollout never waits on the host."""

from __future__ import annotations

import torch


class EpisodeTracker:
    """Per-env running return and length; sums over the episodes that finish, read once per log."""

    def __init__(self, num_envs: int, device: torch.device):
        self.ret = torch.zeros(num_envs, device=device)
        self.length = torch.zeros(num_envs, device=device)
        # finished episodes: count, sum of returns, of lengths, of mean forward speeds, speed count
        self.sums = torch.zeros(5, dtype=torch.float64, device=device)

    def step(self, reward: torch.Tensor, done: torch.Tensor, info: dict) -> torch.Tensor:
        """Fold one step in; return the mask of envs whose episode ended."""
        self.ret += reward
        self.length += 1
        d = done.float()
        speed = info.get("episode", {}).get("s") if isinstance(info, dict) else None
        has_speed = speed is not None
        self.sums += torch.stack([
            d.sum(), (self.ret * d).sum(), (self.length * d).sum(),
            (speed * d).sum() if has_speed else d.new_zeros(()), d.sum() if has_speed else d.new_zeros(()),
        ]).double()
        keep = 1.0 - d
        self.ret *= keep
        self.length *= keep
        return done

    def read_and_clear(self) -> dict:
        """One host read; means of the episodes finished since the last call (None where there were none)."""
        n, r, length, s, ns = self.sums.tolist()
        self.sums.zero_()
        return {
            "episodes": int(n),
            "return": r / n if n else None,
            "length": length / n if n else None,
            "speed": s / ns if ns else None,
        }
