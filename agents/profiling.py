"""Where an iteration's time goes. Off by default: timing a phase on a GPU needs a synchronisation
at its end, which is exactly what the training loop otherwise avoids."""

from __future__ import annotations

import time
from collections import defaultdict

import torch


class PhaseTimer:
    def __init__(self, device: torch.device, enabled: bool = False):
        self.device, self.enabled = device, enabled
        self.seconds: dict[str, float] = defaultdict(float)
        self.iterations = 0
        self._last = 0.0

    def start(self) -> None:
        if self.enabled:
            self._sync()
            self._last = time.perf_counter()

    def lap(self, phase: str) -> None:
        """Charge the time since the previous lap (or start) to ``phase``."""
        if self.enabled:
            self._sync()
            now = time.perf_counter()
            self.seconds[phase] += now - self._last
            self._last = now

    def _sync(self) -> None:
        if self.device.type == "cuda":
            torch.cuda.synchronize(self.device)

    def table(self) -> list[dict]:
        total = sum(self.seconds.values()) or 1.0
        n = max(self.iterations, 1)
        return [{"phase": k, "ms_per_iteration": 1e3 * v / n, "share": v / total}
                for k, v in sorted(self.seconds.items(), key=lambda kv: -kv[1])]
