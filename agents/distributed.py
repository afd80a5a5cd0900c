"""Worker parallelism across GPUs: one process per GPU, each stepping its own envs, one policy.

Launch with ``torchrun --nproc_per_node=G -m warpgym train ...`` (add ``--nnodes`` and a c10d
rendezvous for several machines). Every process collects its own rollouts; gradients, the KL that
steers the learning rate, observation-normaliser statistics and episode statistics are averaged or
summed across processes, so the policies stay identical and the run is one learner with G times
the envs. Rank 0 logs, evaluates and writes checkpoints. With one process every call here is a
no-op. This module is the only one that knows ``torch.distributed``.

A collective waits for every process, and a dead peer never arrives: ``PeerWatch`` notices a
silent peer through the job's store and ends this process with a message instead of a hang.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable
from datetime import timedelta

import torch
import torch.distributed as dist

EXIT_PEER_LOST = 75  # EX_TEMPFAIL: nothing is wrong with this process; resume the run


def init_workers(backend: str, device: torch.device | None = None) -> None:
    """Join the job's process group (torchrun's environment: RANK, WORLD_SIZE, MASTER_ADDR/PORT).

    torch._dynamo (which the optimizer imports lazily) keeps the default process group alive past
    ``destroy_process_group`` when it is first imported after the group exists; Gloo's threads then
    release their last collective's tensors while the interpreter shuts down, which aborts the
    process (SIGABRT, about one exit in ten on a 2-core machine). Imported first, it does not."""
    import torch._dynamo  # noqa: F401, PLC0415

    dist.init_process_group(backend, device_id=device)


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

    def mean_grads_(self, params, *extras: torch.Tensor) -> tuple[torch.Tensor, ...]:
        """Average the gradients and a few scalars (the KL) across processes in one all-reduce.

        No host synchronisation and the same shapes every call, so the mini-batch step that calls
        it can be captured in a CUDA graph, collective included (NCCL >= 2.9)."""
        if not self.active:
            return extras
        grads = [p.grad for p in params if p.grad is not None]
        flat = torch.cat([g.reshape(-1) for g in grads] + [e.reshape(1).to(grads[0].dtype) for e in extras])
        self.mean_(flat)
        offset = 0
        for g in grads:
            g.copy_(flat[offset : offset + g.numel()].view_as(g))
            offset += g.numel()
        return tuple(flat[offset + i].view_as(e).to(e.dtype) for i, e in enumerate(extras))

    def broadcast_bytes(self, data: bytes | None, device: torch.device) -> bytes:
        """Rank 0's bytes on every process (a config or a checkpoint that only rank 0's disk has)."""
        if not self.active:
            return data
        size = torch.tensor([len(data) if self.is_main else 0], dtype=torch.int64, device=device)
        dist.broadcast(size, src=0)
        buf = torch.empty(int(size.item()), dtype=torch.uint8, device=device)
        if self.is_main:
            buf.copy_(torch.frombuffer(bytearray(data), dtype=torch.uint8))
        dist.broadcast(buf, src=0)
        return bytes(buf.cpu().numpy()) if not self.is_main else data


def job_store() -> dist.Store | None:
    """A connection of its own to the job's key-value store (torchrun's), or None outside a job.

    Its own connection, so that a long blocking wait of the main thread on the shared one (a
    communicator's set-up) never delays the watch."""
    addr, port = os.environ.get("MASTER_ADDR"), os.environ.get("MASTER_PORT")
    if not (addr and port):
        return None
    try:
        return dist.TCPStore(addr, int(port), is_master=False, timeout=timedelta(seconds=10))
    except (RuntimeError, ValueError):
        return None


class PeerWatch:
    """Each process writes a heartbeat to the job's store and reads everyone else's; when a peer
    has been silent for ``timeout`` seconds (killed, crashed, its machine gone) or the store itself
    is gone, ``on_lost`` runs (default: say so on stderr and end this process).

    ``stop()`` marks this process as finished on purpose, so that its peers stop watching it."""

    def __init__(self, store: dist.Store, rank: int, size: int, interval: float = 1.0, timeout: float = 30.0,
                 hint: str | Callable[[], str] = "", on_lost=None):
        self.store, self.rank, self.size = store, rank, size
        self.interval, self.timeout, self.hint = interval, timeout, hint
        self.on_lost = on_lost or self._exit
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="warpgym-peer-watch", daemon=True)
        self._thread.start()

    @staticmethod
    def key(rank: int) -> str:
        return f"warpgym/alive/{rank}"

    def _run(self) -> None:
        start = time.monotonic()
        heard = {p: (None, start) for p in range(self.size) if p != self.rank}
        beat = 0
        while not self._stop.wait(self.interval):
            beat += 1
            try:
                self.store.set(self.key(self.rank), str(beat))
                for peer in list(heard):
                    value = self.store.get(self.key(peer)) if self.store.check([self.key(peer)]) else None
                    if value == b"done":
                        del heard[peer]
                    elif value != heard[peer][0]:
                        heard[peer] = (value, time.monotonic())
                    elif time.monotonic() - heard[peer][1] > self.timeout:
                        return self.on_lost(f"worker {peer} has not been heard from for "
                                            f"{time.monotonic() - heard[peer][1]:.0f} s (it died or hangs)")
            except (RuntimeError, ValueError, TimeoutError, OSError) as e:
                if self._stop.is_set():
                    return None
                return self.on_lost(f"the job's store stopped answering ({type(e).__name__}: {e}); "
                                    "the process that held it has ended")
        return None

    def stop(self, finished: bool) -> None:
        """Stop beating. ``finished``: this process is past its last collective, so its peers stop
        watching it; otherwise (it is failing) they notice its silence and stop too."""
        if self._stop.is_set():
            return
        self._stop.set()
        if finished:
            try:
                self.store.set(self.key(self.rank), "done")
            except (RuntimeError, ValueError, TimeoutError, OSError):
                pass

    def message(self, why: str) -> str:
        """What ``_exit`` says. A callable ``hint`` is asked now, not when the watch started: the run
        may have written its first checkpoint since (a hint fixed at the start said there was none)."""
        hint = self.hint() if callable(self.hint) else self.hint
        return (f"warpgym worker {self.rank}: {why}; stopping this worker instead of waiting on a collective "
                f"forever. {hint}")

    def _exit(self, why: str) -> None:
        # os._exit: the main thread may be blocked inside a collective that will never complete (NCCL
        # blocks where gloo raises). Checkpoints are written atomically, so nothing already saved is lost.
        sys.stderr.write(f"\n{self.message(why)}\n")
        sys.stderr.flush()
        os._exit(EXIT_PEER_LOST)
