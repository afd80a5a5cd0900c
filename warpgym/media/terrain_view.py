"""A picture of generated rough ground (warpgym.tasks.legged.terrain), drawn by MuJoCo's renderer from the compiled
geometry: each patch coloured by its kind, the grid seen from above one corner.

    python -m warpgym.media.terrain_view docs/figures/rough_terrain.png --seed 0
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from warpgym.media.render import gl_context
from warpgym.tasks.legged import terrain as tr

# one colour per kind, in the order of the grid's sub_terrains (ROUGH's seven, then repeating)
PALETTE = np.array([(0.62, 0.62, 0.62), (0.27, 0.51, 0.71), (0.80, 0.36, 0.36), (0.40, 0.66, 0.40),
                    (0.85, 0.65, 0.30), (0.58, 0.44, 0.70), (0.35, 0.70, 0.72)])


def compiled(ground: tr.Terrain):
    """The ground's MuJoCo model, each geom coloured by its patch's kind, with a light and a sky-grey background."""
    import mujoco  # noqa: PLC0415

    spec = mujoco.MjSpec()
    spec.worldbody.add_light(pos=[0, 0, 60], dir=[0.3, 0.2, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    tr.add_to_spec(spec, ground)
    kinds = [int(ground.kinds[r, c]) for r in range(ground.grid.num_rows) for c in range(ground.grid.cols)
             for _ in ground.patches[r][c].geoms]
    for geom, kind in zip(spec.body("terrain").geoms, kinds + [-1] * 4):  # the outer border's four last
        geom.rgba = [*(PALETTE[kind % len(PALETTE)] if kind >= 0 else (0.25, 0.25, 0.25)), 1.0]
    return spec.compile()


def draw(ground: tr.Terrain, width: int = 960, height: int = 540) -> np.ndarray:
    """(height, width, 3) uint8: the grid from above its first corner."""
    import mujoco  # noqa: PLC0415

    mjm = compiled(ground)
    mjm.vis.global_.offwidth, mjm.vis.global_.offheight = max(width, 640), max(height, 480)
    data = mujoco.MjData(mjm)
    mujoco.mj_forward(mjm, data)
    context = gl_context(width, height)
    try:
        with mujoco.Renderer(mjm, height, width) as renderer:
            cam = mujoco.MjvCamera()
            g = ground.grid
            cam.lookat[:] = (0.0, 0.0, 0.0)
            cam.distance = 0.75 * max(g.num_rows * g.size[0], g.cols * g.size[1])
            cam.azimuth, cam.elevation = 200.0, -38.0
            renderer.update_scene(data, camera=cam)
            return renderer.render().copy()
    finally:
        context.free()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m warpgym.media.terrain_view", description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="PNG to write")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--width", type=int, default=960)
    ap.add_argument("--height", type=int, default=540)
    args = ap.parse_args(argv)
    from PIL import Image  # noqa: PLC0415

    Image.fromarray(draw(tr.generate(tr.ROUGH, args.seed), args.width, args.height)).save(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
