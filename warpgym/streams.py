"""Ordering between torch's current CUDA stream and the Warp stream the simulation runs on.

torch writes actions into buffers that Warp kernels read, and reads observations that Warp
kernels write. Rather than forcing one stream on the user, each side waits on an event recorded
by the other: a device-side dependency, never a host synchronisation. When torch already runs on
the Warp stream (the training runner does this to capture whole rollouts), both waits are skipped.
"""

from __future__ import annotations

import torch
import warp as wp


class StreamOrder:
    def __init__(self, device: str):
        self.device = device
        self.is_cuda = device.startswith("cuda")
        if self.is_cuda:
            self.warp_stream = wp.get_stream(device)
            self.warp_as_torch = wp.stream_to_torch(self.warp_stream)
            self._wrapped: dict[int, wp.Stream] = {}

    def _torch_stream(self):
        return torch.cuda.current_stream(torch.device(self.device))

    def shares_stream(self) -> bool:
        return not self.is_cuda or self._torch_stream().cuda_stream == self.warp_stream.cuda_stream

    def warp_waits_for_torch(self) -> None:
        if self.shares_stream():
            return
        ts = self._torch_stream()
        ws = self._wrapped.get(ts.cuda_stream)
        if ws is None:
            ws = self._wrapped[ts.cuda_stream] = wp.stream_from_torch(ts)
        self.warp_stream.wait_stream(ws)

    def torch_waits_for_warp(self) -> None:
        if self.shares_stream():
            return
        self._torch_stream().wait_stream(self.warp_as_torch)
