"""The rough ground laid with fewer geoms, for the studies of MuJoCo Warp's collision cost on rough ground
(rough_settings.py, ground_resampling.py). Not mjlab's ground, so not the tasks':

- ``stairs_cell > 0`` lays each patch built of several boxes (the stairs) as one heightfield sampled every this many
  metres (the rough tasks' grid: 74 ground geoms instead of 554); a step's edge becomes a ramp one cell wide;
- ``ground_cell > 0`` lays the whole grid inside the border as one heightfield sampled every this many metres (five
  ground geoms with the border's boxes); every patch is resampled, so the ground moves near a step's edge and between
  a heightfield patch's nodes.

``Resampled.of(grid, ...)`` is a ``TerrainGrid`` that a task takes as its ``terrain``.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from warpgym.tasks.legged.terrain import Box, HField, Patch, Terrain, TerrainGrid, generate


@dataclass(frozen=True)
class Resampled(TerrainGrid):
    stairs_cell: float = 0.0
    ground_cell: float = 0.0

    @classmethod
    def of(cls, grid: TerrainGrid, stairs_cell: float = 0.0, ground_cell: float = 0.0) -> "Resampled":
        return cls(**{f.name: getattr(grid, f.name) for f in fields(TerrainGrid)}, stairs_cell=stairs_cell,
                   ground_cell=ground_cell)

    def __post_init__(self):
        super().__post_init__()
        for name in ("stairs_cell", "ground_cell"):
            cell = getattr(self, name)
            if not (cell == 0.0 or 0.0 < cell <= min(self.size) / 4):
                raise ValueError(f"Resampled: {name}={cell}: give 0 (the patches' own geoms, as mjlab) or a cell size "
                                 f"in metres up to a quarter of the {min(self.size):g}-m patch, e.g. 0.05")
        if self.stairs_cell > 0.0 and self.ground_cell > 0.0:
            raise ValueError(f"Resampled: stairs_cell={self.stairs_cell} and ground_cell={self.ground_cell}: the "
                             "whole ground's heightfield holds the stairs too: give one of them, the other 0")

    def generate(self, seed: int) -> Terrain:
        ground = generate(self, seed)  # mjlab's draws first: the same kinds, difficulties and starts
        if self.ground_cell > 0.0:
            return OneHeightfield(ground.grid, ground.kinds, ground.difficulty, ground.corners, ground.origins,
                                  ground.patches)
        if self.stairs_cell > 0.0:
            for row in ground.patches:
                for c, patch in enumerate(row):
                    if sum(isinstance(g, Box) for g in patch.geoms) > 1:
                        row[c] = Patch(patch.origin, (boxes_to_heightfield(patch.geoms, self.size, self.stairs_cell),))
        return ground


class OneHeightfield(Terrain):
    """A grid whose patches are laid as one heightfield (``Resampled.ground_cell``); drawn in one colour, as its
    kinds cannot be told apart."""

    def patch_geoms(self):
        yield ground_heightfield(self, self.grid.ground_cell)

    def patch_geom_kinds(self) -> list[int]:
        return [0]


def _tops(geoms, x: np.ndarray, y: np.ndarray, offset=(0.0, 0.0)) -> np.ndarray:
    """The highest surface of ``geoms`` (their frame moved by ``offset``) over each point (-inf where none is): a
    box's top, a heightfield's height as MuJoCo lays its data (rows along y, columns along x, each cell two
    triangles)."""
    tops = np.full(x.shape, -np.inf)
    eps = 1e-9
    for g in geoms:
        gx, gy = g.pos[0] + offset[0], g.pos[1] + offset[1]
        if isinstance(g, Box):
            over = (np.abs(x - gx) <= g.half[0] + eps) & (np.abs(y - gy) <= g.half[1] + eps)
            tops = np.where(over, np.maximum(tops, g.pos[2] + g.half[2]), tops)
            continue
        nrow, ncol = g.data.shape
        over = (np.abs(x - gx) <= g.size[0] + eps) & (np.abs(y - gy) <= g.size[1] + eps)
        u = np.clip((x - gx + g.size[0]) / (2 * g.size[0]) * (ncol - 1), 0, ncol - 1)
        v = np.clip((y - gy + g.size[1]) / (2 * g.size[1]) * (nrow - 1), 0, nrow - 1)
        c0, r0 = np.minimum(u.astype(int), ncol - 2), np.minimum(v.astype(int), nrow - 2)
        fu, fv = u - c0, v - r0
        h00, h10 = g.data[r0, c0], g.data[r0, c0 + 1]
        h01, h11 = g.data[r0 + 1, c0], g.data[r0 + 1, c0 + 1]
        # MuJoCo's two triangles of a cell share the diagonal from node (r, c) to node (r + 1, c + 1)
        level = np.where(fu >= fv, h00 + fu * (h10 - h00) + fv * (h11 - h10),
                         h00 + fv * (h01 - h00) + fu * (h11 - h01))
        tops = np.where(over, np.maximum(tops, g.pos[2] + g.size[2] * level), tops)
    return tops


def _as_heightfield(tops: np.ndarray, center, half, low: float) -> HField:
    """Sampled heights (rows along y) as one heightfield centred at ``center``; its base reaches down to ``low``."""
    lo, hi = float(tops.min()), float(tops.max())
    elevation = max(hi - lo, 1e-6)  # MuJoCo needs a positive elevation
    base = max(lo - low, 0.05)  # down to the ground's bottom, at least 5 cm
    data = ((tops - lo) / elevation).astype(np.float32)
    return HField((center[0], center[1], lo), (half[0], half[1], elevation, base), data)


def boxes_to_heightfield(boxes, size, cell: float) -> HField:
    """The ground a patch's boxes make, sampled every ``cell`` metres as one heightfield over the patch: at each
    sample the highest top of the boxes over it. Between two samples MuJoCo interpolates, so a vertical face becomes a
    slope one cell wide; everywhere else the surface is the boxes'."""
    n = int(round(size[0] / cell)) + 1, int(round(size[1] / cell)) + 1
    x, y = np.meshgrid(np.linspace(0.0, size[0], n[0]), np.linspace(0.0, size[1], n[1]))  # MuJoCo's order
    low = min(b.pos[2] - b.half[2] for b in boxes)
    tops = _tops(boxes, x, y)
    return _as_heightfield(np.where(np.isfinite(tops), tops, low), (size[0] / 2, size[1] / 2),
                           (size[0] / 2, size[1] / 2), low)


def ground_heightfield(terrain, cell: float) -> HField:
    """Every patch of ``terrain`` sampled every ``cell`` metres into one heightfield over the grid inside the border
    (world frame): the highest surface of a patch's geoms at each sample, the higher patch's on a shared edge."""
    grid = terrain.grid
    extent = grid.num_rows * grid.size[0], grid.cols * grid.size[1]
    x0, y0 = terrain.corners[0, 0, 0], terrain.corners[0, 0, 1]
    xs = x0 + np.linspace(0.0, extent[0], int(round(extent[0] / cell)) + 1)
    ys = y0 + np.linspace(0.0, extent[1], int(round(extent[1] / cell)) + 1)
    tops = np.full((len(ys), len(xs)), -np.inf)  # rows along y: MuJoCo's order
    low = 0.0
    for r in range(grid.num_rows):
        for c in range(grid.cols):
            corner, patch = terrain.corners[r, c], terrain.patches[r][c]
            # only the samples on this patch (its edges included): a patch's geoms reach no further
            i = slice(*np.searchsorted(xs, [corner[0] - 1e-9, corner[0] + grid.size[0] + 1e-9]))
            j = slice(*np.searchsorted(ys, [corner[1] - 1e-9, corner[1] + grid.size[1] + 1e-9]))
            x, y = np.meshgrid(xs[i], ys[j])
            tops[j, i] = np.maximum(tops[j, i], _tops(patch.geoms, x, y, offset=corner[:2]))
            low = min(low, *(g.pos[2] - (g.half[2] if isinstance(g, Box) else g.size[3]) for g in patch.geoms))
    tops = np.where(np.isfinite(tops), tops, low)
    return _as_heightfield(tops, (x0 + extent[0] / 2, y0 + extent[1] / 2), (extent[0] / 2, extent[1] / 2), low)
