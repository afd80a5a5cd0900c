"""Where the worlds of a rough-ground task start (mjlab's ``TerrainEntity`` in curriculum mode): each world keeps
one kind of ground (a column), the worlds shared among the kinds by their proportions; its first level is drawn
uniformly up to ``max_init_level``. The levels then move with the curriculum (``kernels.legged.terrain_levels``).
"""

from __future__ import annotations

import numpy as np

from warpgym.tasks.legged.terrain import Terrain


def proportional_counts(num_envs: int, proportions) -> np.ndarray:
    """``num_envs`` shared among buckets by ``proportions`` (summing to 1): one each first when there are enough,
    the rest by their floors, then one more to the largest remainders."""
    p = np.asarray(proportions, dtype=np.float64)
    counts = np.ones(len(p), dtype=np.int64) if num_envs >= len(p) else np.zeros(len(p), dtype=np.int64)
    left = num_envs - int(counts.sum())
    if left > 0:
        ideal = p * left
        floor = np.floor(ideal).astype(np.int64)
        counts += floor
        extra = left - int(floor.sum())
        if extra > 0:
            counts[np.argsort(-(ideal - floor), kind="stable")[:extra]] += 1
    return counts


def start_levels(terrain: Terrain, num_envs: int, max_init_level: int, rng: np.random.Generator):
    """Each world's first level and its kind: (levels, kinds), each (num_envs,) int32."""
    grid = terrain.grid
    if not grid.curriculum:
        raise ValueError("the terrain curriculum needs a grid made with curriculum=True (one kind per column)")
    if not (isinstance(max_init_level, int) and max_init_level >= 0):
        raise ValueError(f"max_init_level={max_init_level!r}: pass a level >= 0 (mjlab's rough tasks: 5)")
    top = min(max_init_level, grid.num_rows - 1)
    levels = rng.integers(0, top + 1, size=num_envs)
    weights = np.array([sub.proportion for _, sub in grid.sub_terrains], dtype=np.float64)
    kinds = np.repeat(np.arange(grid.cols), proportional_counts(num_envs, weights / weights.sum()))
    return levels.astype(np.int32), kinds.astype(np.int32)


def bounds(terrain: Terrain, margin: float = 0.3) -> tuple[float, float]:
    """mjlab's out_of_terrain_bounds: half the ground's extent (border included) less ``margin``, in x and y."""
    g = terrain.grid
    half_x = 0.5 * g.num_rows * g.size[0] + g.border_width
    half_y = 0.5 * g.cols * g.size[1] + g.border_width
    return max(0.0, half_x - margin), max(0.0, half_y - margin)
