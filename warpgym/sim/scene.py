"""A scene file compiled by MuJoCo itself, for MuJoCo Warp: the model the legged tasks simulate."""

from __future__ import annotations

import os

from warpgym.sim.gym_model import CompiledModel


def compile_scene(path: str) -> CompiledModel:
    """``mujoco.MjModel.from_xml_path(path)``, the file's own physics."""
    import mujoco  # noqa: PLC0415

    if not os.path.isfile(path):
        raise FileNotFoundError(f"scene file {path} does not exist: pass scene_file= the path of an MJCF file")
    return CompiledModel(mujoco.MjModel.from_xml_path(path), path)
