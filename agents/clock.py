"""The iteration clock: where each training iteration's time goes, on the device's own clock.

On CUDA every mark is an event recorded on the current stream, so marking costs no host
synchronisation; an iteration's marks are read one iteration later, when they have long completed.
On the CPU, where every op has finished when it returns, a mark is the time.

An iteration runs from the end of the previous one to its own end, so time the GPU spends idle
between them (waiting on the host) counts against it. Work that is not training (an evaluation)
is cut out with ``restart()``: the next iteration then starts after it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import torch


@dataclass
class Lap:
    """One iteration's marks: its start, then (phase, end of that phase) in order."""

    start: object
    marks: list[tuple[str, object]] = field(default_factory=list)


class IterationClock:
    def __init__(self, device: torch.device):
        self.device = device
        self.is_cuda = device.type == "cuda"
        self._lap = Lap(self._now())

    def _now(self):
        if not self.is_cuda:
            return time.perf_counter()
        event = torch.cuda.Event(enable_timing=True)
        event.record(torch.cuda.current_stream(self.device))
        return event

    def mark(self, phase: str) -> None:
        """The work queued so far, since the previous mark, belongs to ``phase``."""
        self._lap.marks.append((phase, self._now()))

    def finish(self) -> Lap:
        """Close the current iteration (its last mark is its end); the next one starts there."""
        lap = self._lap
        self._lap = Lap(lap.marks[-1][1] if lap.marks else self._now())
        return lap

    def restart(self) -> None:
        """Leave out what was queued since the last iteration ended (an evaluation, say)."""
        self._lap = Lap(self._now())

    def seconds(self, lap: Lap) -> dict[str, float]:
        """Seconds of each phase of ``lap`` and of the whole iteration (``"iteration"``).

        Waits for the lap's end on the device; called one iteration late, that wait is over."""
        if self.is_cuda and lap.marks:
            lap.marks[-1][1].synchronize()
        out: dict[str, float] = {}
        prev = lap.start
        for phase, mark in lap.marks:
            out[phase] = out.get(phase, 0.0) + self._between(prev, mark)
            prev = mark
        out["iteration"] = self._between(lap.start, prev)
        return out

    def _between(self, a, b) -> float:
        return a.elapsed_time(b) / 1e3 if self.is_cuda else b - a
