"""Running mean and variance of observations, kept on the device and merged batch by batch."""

from __future__ import annotations

import torch
from torch import nn


class RunningMeanStd(nn.Module):
    """``until``: once the statistics hold at least this many observations they stay as they are (the batch
    that crosses it is learnt whole); 0 learns from every batch."""

    def __init__(self, size: int, clip: float = 5.0, eps: float = 1e-8, until: float = 0):
        super().__init__()
        self.clip = clip
        self.eps = eps
        self.until = until
        self.register_buffer("mean", torch.zeros(size))
        self.register_buffer("var", torch.ones(size))
        self.register_buffer("count", torch.zeros((), dtype=torch.float64))

    @torch.no_grad()
    def update(self, x: torch.Tensor, workers=None) -> None:
        """Fold a batch (B, size) into the statistics (Chan et al.'s parallel merge); no host sync.

        With ``workers`` (agents.distributed.Workers), the batch is every process's batch together.
        """
        size = self.mean.shape[0]
        x = x.reshape(-1, size).double()
        moments = torch.cat([x.new_full((1,), x.shape[0]), x.sum(0), (x * x).sum(0)])
        if workers is not None:
            workers.sum_(moments)
        n = moments[0]
        batch_mean = moments[1 : 1 + size] / n
        batch_var = (moments[1 + size :] / n - batch_mean * batch_mean).clamp(min=0.0)
        total = self.count + n
        w = n / total
        if self.until > 0:  # decided on the device: the update stays free of host syncs and capturable
            learning = (self.count < self.until).double()  # 1 or 0: a batch past the limit weighs nothing
            w = w * learning
            total = self.count + n * learning
        delta = batch_mean - self.mean
        self.mean.add_((delta * w).float())
        self.var.copy_((self.var * (1 - w) + batch_var * w + delta * delta * w * (1 - w)).float())
        self.count.copy_(total)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return ((x - self.mean) / torch.sqrt(self.var + self.eps)).clamp(-self.clip, self.clip)
