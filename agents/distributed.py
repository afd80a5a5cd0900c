"""Worker parallelism across GPUs: one process per GPU, each stepping its own envs, one policy.

Launch with ``torchrun --nproc_per_node=G scripts/train.py ...``. Every process collects its own
rollouts; gradients, the KL that steers the learning rate, observation-normaliser statistics and
episode statistics are averaged or summed across processes, so the policies stay identical and the
run behaves like one learner with G times the envs. Rank 0 logs, evaluates and writes checkpoints.
With one process every call here is a no-op.
"""

from __future__ import annotations

import torch
import torch.distributed as dist


class Workers:
    def __init__(self):
        self.active = dist.is_available() and dist.is_initialized() and dist.get_world_size() > 1
        self.rank = dist.get_rank() if self.active else 0
        self.size = dist.get_world_size() if self.active else 1

    @property
    def is_main(self) -> bool:
        return self.rank == 0

    def broadcast_(self, tensors) -> None:
        """Give every process rank 0's values of these tensors."""
        if self.active:
            with torch.no_grad():
                for t in tensors:
                    dist.broadcast(t.data, src=0)

    def sum_(self, t: torch.Tensor) -> torch.Tensor:
        if self.active:
            dist.all_reduce(t, op=dist.ReduceOp.SUM)
        return t

    def mean_(self, t: torch.Tensor) -> torch.Tensor:
        if self.active:
            dist.all_reduce(t, op=dist.ReduceOp.SUM)
            t /= self.size
        return t

    def mean_grads_(self, params) -> None:
        """Average gradients across processes in one flat all-reduce."""
        if not self.active:
            return
        grads = [p.grad for p in params if p.grad is not None]
        flat = torch.cat([g.reshape(-1) for g in grads])
        self.mean_(flat)
        offset = 0
        for g in grads:
            g.copy_(flat[offset : offset + g.numel()].view_as(g))
            offset += g.numel()

    def agree(self, flag: bool, device: torch.device) -> bool:
        """Rank 0's decision, for choices (like stopping on a time limit) that must not diverge."""
        if not self.active:
            return flag
        t = torch.tensor([1.0 if flag else 0.0], device=device)
        dist.broadcast(t, src=0)
        return bool(t.item())
