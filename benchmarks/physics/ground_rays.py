"""MuJoCo's own ray casts onto a generated ground: the judge of warpgym's terrain generator against mjlab's (the
same rays on both compiles, tests/test_terrain.py) and the measure of the ground studies (ground_variants.py)."""

from __future__ import annotations

import math

import numpy as np


def compile_alone(terrain):
    """``terrain`` (a ``warpgym.tasks.legged.terrain.Terrain``) alone, without robot or light, compiled by MuJoCo: the
    model ``heights`` casts its rays onto."""
    import mujoco  # noqa: PLC0415

    from warpgym.tasks.legged.terrain import add_to_spec  # noqa: PLC0415

    spec = mujoco.MjSpec()
    add_to_spec(spec, terrain)
    return spec.compile()


def heights(mjm, points: np.ndarray, top: float = 10.0, bodyexclude: int = -1) -> np.ndarray:
    """The ground's height under each (x, y) of ``points``: MuJoCo's ray cast straight down from ``top`` (NaN where
    nothing is hit)."""
    import mujoco  # noqa: PLC0415

    data = mujoco.MjData(mjm)
    mujoco.mj_forward(mjm, data)
    out = np.full(len(points), math.nan)
    geomid = np.zeros(1, dtype=np.int32)
    for i, (x, y) in enumerate(points):
        dist = mujoco.mj_ray(mjm, data, np.array([x, y, top]), np.array([0.0, 0.0, -1.0]), None, 1, bodyexclude, geomid)
        if dist >= 0:
            out[i] = top - dist
    return out


def kinds_at(terrain, points: np.ndarray) -> np.ndarray:
    """The kind (an index into ``terrain.grid.sub_terrains``) of the patch under each (x, y) of ``points``, world
    frame; a point on the border counts as the nearest patch's."""
    g = terrain.grid
    rc = np.floor((np.asarray(points)[:, :2] - terrain.corners[0, 0, :2]) / np.asarray(g.size)).astype(int)
    rc = np.clip(rc, 0, [g.num_rows - 1, g.cols - 1])
    return terrain.kinds[rc[:, 0], rc[:, 1]]
