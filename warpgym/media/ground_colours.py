"""Generated rough ground drawn in colour: each patch by its kind of ground, so that a picture or a clip shows which
kind a robot is on (the ground's own geoms are all one grey)."""

from __future__ import annotations

import numpy as np

# one colour per kind, in the order of the grid's sub_terrains (mjlab's seven rough kinds, then repeating)
PALETTE = np.array([(0.62, 0.62, 0.62), (0.27, 0.51, 0.71), (0.80, 0.36, 0.36), (0.40, 0.66, 0.40),
                    (0.85, 0.65, 0.30), (0.58, 0.44, 0.70), (0.35, 0.70, 0.72)])
BORDER = (0.25, 0.25, 0.25)


def colour_ground(mjm, ground) -> None:
    """Colour the geoms of ``mjm``'s ``terrain`` body (as ``warpgym.tasks.legged.terrain.add_to_spec`` laid them:
    ``ground.boxes_and_fields()``: its patches' geoms, then the outer border) by their patch's kind
    (``ground.patch_geom_kinds()``)."""
    import mujoco  # noqa: PLC0415

    body = mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_BODY, "terrain")
    geoms = np.flatnonzero(mjm.geom_bodyid == body)
    kinds = ground.patch_geom_kinds()
    if len(geoms) != len(kinds) + 4:
        raise ValueError(f"the terrain body holds {len(geoms)} geoms, the ground {len(kinds)} and a border of 4: "
                         "colour the model compiled from this ground")
    for geom, kind in zip(geoms, kinds + [-1] * 4):
        mjm.geom_rgba[geom] = [*(PALETTE[kind % len(PALETTE)] if kind >= 0 else BORDER), 1.0]
