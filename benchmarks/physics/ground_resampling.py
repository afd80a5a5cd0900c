"""How far the rough ground laid as one heightfield (ground_variants.py's ``ground_cell``) moves from mjlab's, kind
by kind: MuJoCo's ray casts straight down onto both compiles at the same random points over the grid, the median,
95th percentile and largest height difference of each kind of patch, and how long MuJoCo takes to compile each.
CPU only, a few seconds a cell size.

    python -m benchmarks.physics.ground_resampling --cells 0.05 0.025 --points 4000
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

import numpy as np


def compile_ground(grid, seed: int):
    """(Terrain, MjModel, seconds to generate and compile it)."""
    from benchmarks.physics.ground_rays import compile_alone  # noqa: PLC0415

    start = time.perf_counter()
    ground = grid.generate(seed)
    model = compile_alone(ground)
    return ground, model, time.perf_counter() - start


def differences(cells: list[float], points: int, seed: int) -> list[dict]:
    """Each cell size's row: its heightfield's nodes, compile time and, per kind, the height differences [m]."""
    from benchmarks.physics.ground_rays import heights, kinds_at  # noqa: PLC0415
    from benchmarks.physics.ground_variants import Resampled  # noqa: PLC0415
    from warpgym.tasks.legged import terrain as tr  # noqa: PLC0415

    grid = replace(tr.ROUGH, curriculum=True)  # as the rough tasks build it: one kind a column
    ground, reference, _ = compile_ground(grid, seed)
    corner = ground.corners[0, 0, :2]
    extent = np.array([grid.num_rows * grid.size[0], grid.cols * grid.size[1]])
    at = corner + np.random.default_rng(seed).uniform(0.0, 1.0, (points, 2)) * extent
    want = heights(reference, at)
    kinds = kinds_at(ground, at)
    rows = []
    for cell in cells:
        _, model, seconds = compile_ground(Resampled.of(grid, ground_cell=cell), seed)
        err = np.abs(heights(model, at) - want)
        by_kind = {name: [float(np.median(err[kinds == k])), float(np.percentile(err[kinds == k], 95)),
                          float(err[kinds == k].max())]
                   for k, (name, _) in enumerate(grid.sub_terrains) if (kinds == k).any()}
        rows.append({"cell": cell, "nodes": [int(model.hfield_ncol[0]), int(model.hfield_nrow[0])],
                     "ground_geoms": int(model.ngeom), "compile_s": round(seconds, 2), "by_kind": by_kind})
    return rows


def table(rows: list[dict]) -> str:
    mm = lambda v: "0" if v < 5e-5 else f"{1e3 * v:.1f} mm"  # noqa: E731
    kinds = list(rows[0]["by_kind"])
    out = ["| kind | " + " | ".join(f"{r['cell'] * 100:g} cm cells: median / 95 % / largest" for r in rows) + " |",
           "|---|" + "---|" * len(rows)]
    out += [f"| {k} | " + " | ".join(" / ".join(mm(v) for v in r["by_kind"][k]) for r in rows) + " |" for k in kinds]
    out += ["", "; ".join(f"{r['cell'] * 100:g} cm: {r['nodes'][0]} x {r['nodes'][1]} nodes, {r['ground_geoms']} "
                          f"ground geoms, generated and compiled in {r['compile_s']:.2f} s" for r in rows)]
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cells", type=float, nargs="+", default=[0.05, 0.025], help="cell sizes [m] (default 0.05 0.025)")
    ap.add_argument("--points", type=int, default=4000, help="rays spread uniformly over the grid (default 4000)")
    ap.add_argument("--seed", type=int, default=0, help="the terrain's seed and the points' (default 0)")
    args = ap.parse_args(argv)
    if args.points < 1:
        ap.error(f"--points {args.points}: give 1 or more, e.g. 4000")
    print(table(differences(args.cells, args.points, args.seed)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
