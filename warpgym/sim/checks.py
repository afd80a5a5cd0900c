"""Input checks shared by the Tensor API and the environments (each error names the value and the fix), and which of
MuJoCo Warp's overflow flags the sims count as lost physics."""

from __future__ import annotations

import numpy as np
import torch


def check_positive_int(name: str, value, fix: str) -> int:
    """Accept a positive integer (not a bool); the error names the value and ``fix``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ValueError(f"{name}={value!r} must be a positive integer: {fix}")
    return int(value)


def check_float_tensor(name: str, t, device: torch.device, shapes: list[tuple[int, ...]]) -> torch.Tensor:
    """Accept a float32 tensor on ``device`` whose shape is one of ``shapes``; return it contiguous."""
    if not isinstance(t, torch.Tensor):
        raise TypeError(f"{name} must be a torch.Tensor, got {type(t).__name__}; wrap it with torch.as_tensor")
    if t.device != device:
        raise ValueError(f"{name} is on {t.device} but the sim runs on {device}: pass {name}.to('{device}')")
    if t.dtype != torch.float32:
        raise TypeError(f"{name} has dtype {t.dtype}; the sim takes torch.float32: pass {name}.float()")
    if tuple(t.shape) not in shapes:
        want = " or ".join(str(s) for s in shapes)
        raise ValueError(f"{name} has shape {tuple(t.shape)}; expected {want}")
    return t.contiguous()


def check_env_ids(name: str, ids, device: torch.device, num_envs: int, check_range: bool) -> torch.Tensor:
    """Accept a 1-D integer tensor of env indices; return it as contiguous int32."""
    if not isinstance(ids, torch.Tensor):
        raise TypeError(f"{name} must be a torch.Tensor of env indices, got {type(ids).__name__}")
    if ids.dtype not in (torch.int32, torch.int64):
        raise TypeError(f"{name} has dtype {ids.dtype}; pass int32 or int64 indices ({name}.int())")
    if ids.device != device:
        raise ValueError(f"{name} is on {ids.device} but the sim runs on {device}: pass {name}.to('{device}')")
    if ids.dim() != 1:
        raise ValueError(f"{name} has shape {tuple(ids.shape)}; pass a 1-D tensor of env indices")
    if check_range and ids.numel() > 0:
        lo, hi = int(ids.min()), int(ids.max())
        if lo < 0 or hi >= num_envs:
            bad = lo if lo < 0 else hi
            raise IndexError(f"{name} holds index {bad}, outside [0, {num_envs - 1}]: pass indices of existing envs")
    return ids.to(torch.int32).contiguous()


def solver_overflow_bits() -> tuple[int, int]:
    """MuJoCo Warp's overflow flags as two masks: those that mean constraints or contacts were dropped (counted on
    the device every substep, ``kernels.solver_load``, and reported once), and those it may still print per world
    (``opt.warn_overflow &= quiet``). The iteration caps are a deliberate speed/accuracy trade, not an error."""
    from mujoco_warp import OverflowType as OF  # noqa: PLC0415

    # HFIELD: a geom over more heightfield prisms than MuJoCo's mjMAXCONPAIR loses the rest as contacts
    drop = int(OF.NEFC | OF.NJMAX_NNZ | OF.BROADPHASE | OF.NARROWPHASE | OF.HFIELD)
    return drop, ~int(OF.ITERATIONS | OF.LS_ITERATIONS | drop)
