"""Device names shared by Warp and torch, checked once, with errors that say what to do."""

from __future__ import annotations

import torch
import warp as wp


def default_device() -> str:
    return "cuda:0" if torch.cuda.is_available() and wp.get_cuda_device_count() > 0 else "cpu"


def resolve_device(device: str | None) -> str:
    """Return a canonical device name ("cpu" or "cuda:N") that both Warp and torch can use."""
    if device is None:
        return default_device()
    name = str(device).strip().lower()
    if name == "cuda":
        name = "cuda:0"
    if name == "cpu":
        return name
    if not name.startswith("cuda:") or not name[5:].isdigit():
        raise ValueError(f"device {device!r} is not a device name: use 'cpu' or 'cuda:N' (e.g. 'cuda:0')")
    index = int(name[5:])
    count = wp.get_cuda_device_count()
    if index >= count or not torch.cuda.is_available():
        found = ", ".join(["cpu"] + [f"cuda:{i}" for i in range(count)])
        raise ValueError(
            f"device {device!r} is not on this machine (found: {found}); pass device='cpu' or one of those"
        )
    return name


def torch_device(device: str) -> torch.device:
    return torch.device(device)
