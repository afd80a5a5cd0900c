"""A picture of generated rough ground (warpgym.tasks.legged.terrain), drawn by MuJoCo's renderer from the compiled
geometry: each patch coloured by its kind, the grid seen from above one corner.

    python -m warpgym.media.terrain_view docs/figures/rough_terrain.png --seed 0
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from warpgym.media.ground_colours import colour_ground
from warpgym.media.render import gl_context
from warpgym.tasks.legged import terrain as tr

def compiled(ground: tr.Terrain):
    """The ground's MuJoCo model, each geom coloured by its patch's kind, with a light and a sky-grey background."""
    import mujoco  # noqa: PLC0415

    spec = mujoco.MjSpec()
    spec.worldbody.add_light(pos=[0, 0, 60], dir=[0.3, 0.2, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    tr.add_to_spec(spec, ground)
    mjm = spec.compile()
    colour_ground(mjm, ground)
    return mjm


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
