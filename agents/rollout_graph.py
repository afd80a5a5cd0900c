"""A rollout captured as CUDA graphs and replayed, so that collecting costs no Python per step.

Two ways to capture (``OnPolicyRunner(rollout_graph=...)``):

- ``"step"``: one env step (policy, env, storage writes at a step index held on the device) is
  captured once and replayed ``horizon`` times, then the bootstrap and GAE as a second graph. The
  capture records one step's launches: a MuJoCo Warp step launches hundreds of kernels per physics
  step, and recording every one of ``horizon`` steps took 17-24 s of a start on an H100 (Ant-v5 and
  Hopper-v5, 32 steps).
- ``"rollout"``: all ``horizon`` steps unrolled into one graph, replayed once.

Both replay the same launches in the same order, so both give what the eager rollout gives.
"""

from __future__ import annotations

from typing import Callable

import torch

ROLLOUT_GRAPHS = ("step", "rollout", "off")


class StepGraphs:
    """The step graph ``horizon`` times, then the finishing graph: what ``torch.cuda.CUDAGraph.replay``
    does for a rollout captured whole."""

    def __init__(self, step: torch.cuda.CUDAGraph, finish: torch.cuda.CUDAGraph, horizon: int):
        self.step, self.finish, self.horizon = step, finish, horizon

    def replay(self) -> None:
        for _ in range(self.horizon):
            self.step.replay()
        self.finish.replay()


def capture_rollout(mode: str, step: Callable[[], None], finish: Callable[[], None], horizon: int,
                    device: torch.device):
    """Capture ``horizon`` calls of ``step`` and one of ``finish`` (``mode``: "step" or "rollout"); an
    object whose ``replay()`` runs them. Nothing runs while capturing."""
    if mode not in ("step", "rollout"):
        raise ValueError(f"rollout graph {mode!r}: capture 'step' or 'rollout'")
    with torch.cuda.device(device):
        if mode == "rollout":
            graph = torch.cuda.CUDAGraph()
            # thread_local: a watchdog thread (NCCL's) may query events while this thread captures
            with torch.cuda.graph(graph, capture_error_mode="thread_local"):
                for _ in range(horizon):
                    step()
                finish()
            return graph
        one, last = torch.cuda.CUDAGraph(), torch.cuda.CUDAGraph()
        with torch.cuda.graph(one, capture_error_mode="thread_local"):
            step()
        # one pool: the two always replay in the order they were captured, never at once
        with torch.cuda.graph(last, pool=one.pool(), capture_error_mode="thread_local"):
            finish()
        return StepGraphs(one, last, horizon)
