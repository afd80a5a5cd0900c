"""The ground scans of mjlab's rough velocity tasks, as ray patterns fixed to a frame (the cast is
``warpgym.sim.rays``): the height scan the policy and the critic see (a grid under the base) and the foot height
scan (a ring under each foot).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def grid_offsets(size: tuple[float, float], resolution: float) -> np.ndarray:
    """mjlab's ``GridPatternCfg``: points every ``resolution`` metres over ``size`` (length along x, width along y),
    centred on the frame, x running fastest; (R, 3) float32."""
    if not (resolution > 0 and all(s >= 0 for s in size)):
        raise ValueError(f"grid size={size!r}, resolution={resolution!r}: pass sizes >= 0 and a resolution > 0 [m]")
    # float32 steps from the float32 start, as torch.arange makes them
    xs = np.arange(-size[0] / 2, size[0] / 2 + resolution * 0.5, resolution, dtype=np.float32)
    ys = np.arange(-size[1] / 2, size[1] / 2 + resolution * 0.5, resolution, dtype=np.float32)
    gx, gy = np.meshgrid(xs, ys, indexing="xy")
    out = np.zeros((gx.size, 3), dtype=np.float32)
    out[:, 0], out[:, 1] = gx.ravel(), gy.ravel()
    return out


def ring_offsets(radius: float, num_samples: int, include_center: bool = True) -> np.ndarray:
    """mjlab's ``RingPatternCfg.single_ring``: the centre (when included), then ``num_samples`` points evenly round
    a circle of ``radius`` from the frame's x axis counter-clockwise; (R, 3) float32."""
    if not (radius >= 0 and isinstance(num_samples, int) and num_samples >= 0):
        raise ValueError(f"ring radius={radius!r}, num_samples={num_samples!r}: pass a radius >= 0 and a count >= 0")
    points = [(0.0, 0.0, 0.0)] if include_center else []
    for i in range(num_samples):
        a = 2.0 * math.pi * i / num_samples
        points.append((radius * math.cos(a), radius * math.sin(a), 0.0))
    if not points:
        raise ValueError("a ring of no samples and no centre casts no ray: pass num_samples >= 1 or include_center")
    return np.asarray(points, dtype=np.float32)


@dataclass(frozen=True)
class ScanPattern:
    """A scan's settings: its rays' offsets in the frame, their direction, alignment and reach, and the geom groups
    they may hit."""

    offsets: tuple  # ((x, y, z), ...)
    direction: tuple[float, float, float] = (0.0, 0.0, -1.0)
    alignment: str = "yaw"
    max_distance: float = 5.0
    groups: tuple[int, ...] = (0,)  # mjlab's terrain only

    def array(self) -> np.ndarray:
        return np.asarray(self.offsets, dtype=np.float32).reshape(-1, 3)


def normal_picks(num_rays: int, max_points: int = 32) -> np.ndarray:
    """The rays mjlab fits the ground's normal to: ``max_points`` of them evenly spaced (torch's float32
    ``linspace``, truncated), or all when there are no more."""
    import torch  # noqa: PLC0415

    if num_rays <= max_points:
        return np.arange(num_rays, dtype=np.int32)
    return torch.linspace(0, num_rays - 1, max_points).long().numpy().astype(np.int32)


def pattern(offsets: np.ndarray, **kwargs) -> ScanPattern:
    return ScanPattern(offsets=tuple(tuple(float(v) for v in p) for p in offsets), **kwargs)


# mjlab's make_velocity_env_cfg: the terrain scan under the base (17 x 11 rays), the feet's within 1 m
TERRAIN_SCAN = pattern(grid_offsets((1.6, 1.0), 0.1), max_distance=5.0)
GO1_FOOT_SCAN = pattern(ring_offsets(0.04, 4), max_distance=1.0)
G1_FOOT_SCAN = pattern(ring_offsets(0.03, 6), max_distance=1.0)
