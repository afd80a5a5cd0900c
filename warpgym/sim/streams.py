"""Ordering between torch's current CUDA stream and the Warp stream the simulation runs on.

torch writes actions into buffers that Warp kernels read, and reads observations that Warp
kernels write. Rather than forcing one stream on the user, each side waits on an event recorded
by the other: a device-side dependency, never a host synchronisation. When torch already runs on
the Warp stream, both waits are skipped.

When torch is capturing a CUDA graph (a learner capturing a whole rollout: policy, env step,
storage), the simulation's launches join that capture instead: they go onto torch's capturing
stream, inside a Warp capture marked external so that Warp's own capture-aware code (conditional
solver loops, allocations) knows where it is.
"""

from __future__ import annotations

import torch
import warp as wp


class StreamOrder:
    def __init__(self, device: str):
        self.device = device
        self.is_cuda = device.startswith("cuda")
        if self.is_cuda:
            self.torch_device = torch.device(device)
            self.warp_stream = wp.get_stream(device)
            self.warp_as_torch = wp.stream_to_torch(self.warp_stream)
            self._wrapped: dict[int, wp.Stream] = {}

    def _torch_stream(self):
        return torch.cuda.current_stream(self.torch_device)

    def _as_warp(self, ts) -> wp.Stream:
        ws = self._wrapped.get(ts.cuda_stream)
        if ws is None:
            ws = self._wrapped[ts.cuda_stream] = wp.stream_from_torch(ts)
        return ws

    def shares_stream(self) -> bool:
        return not self.is_cuda or self._torch_stream().cuda_stream == self.warp_stream.cuda_stream

    def torch_is_capturing(self) -> bool:
        return self.is_cuda and torch.cuda.is_current_stream_capturing()

    def warp_waits_for_torch(self) -> None:
        if self.shares_stream():
            return
        self.warp_stream.wait_stream(self._as_warp(self._torch_stream()))

    def torch_waits_for_warp(self) -> None:
        if self.shares_stream():
            return
        self._torch_stream().wait_stream(self.warp_as_torch)

    def run_in_torch_capture(self, fn) -> None:
        """Launch ``fn``'s Warp work into the CUDA graph torch is capturing on its current stream."""
        ws = self._as_warp(self._torch_stream())
        with wp.ScopedCapture(device=self.device, stream=ws, external=True):
            with wp.ScopedStream(ws, sync_enter=False, sync_exit=False):
                fn()


class CapturedLaunches:
    """``capture`` and ``launch`` of a simulator's step: what ``Sim`` and ``MjwSim`` share. The class using
    it has ``device``, ``_order`` (a ``StreamOrder``), ``_graph`` and ``compile_ahead(fn)``; ``simulate()``
    is one control step as plain launches."""

    def capture(self, fn):
        """Capture ``fn``'s launches as one graph: a CUDA graph, or on the CPU Warp's recorded launch list,
        replayed in C++ (a CPU step is mostly Python launch overhead otherwise). Return None while torch is
        capturing: ``launch`` then records ``fn`` into torch's graph."""
        if self._order.torch_is_capturing():
            return None
        self.compile_ahead(fn)
        with wp.ScopedCapture(device=self.device) as cap:
            fn()
        return cap.graph

    def launch(self, graph, fn) -> None:
        """Run ``fn`` (captured as ``graph``), ordered after and before torch's stream. While torch captures
        a CUDA graph, ``fn``'s launches are recorded into it instead."""
        if self._order.torch_is_capturing():
            self._order.run_in_torch_capture(fn)
            return
        self._order.warp_waits_for_torch()
        if graph is not None:
            wp.capture_launch(graph)
        else:
            fn()
        self._order.torch_waits_for_warp()

    def step(self) -> None:
        """Advance every world one control step."""
        if self._graph is None:
            self._graph = self.capture(self.simulate)
        self.launch(self._graph, self.simulate)
