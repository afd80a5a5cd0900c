"""A scene file compiled by MuJoCo itself, for MuJoCo Warp: the model the legged tasks simulate."""

from __future__ import annotations

import os

from warpgym.sim.gym_model import CompiledModel


def compile_scene(path: str, edit=None) -> CompiledModel:
    """``mujoco.MjModel.from_xml_path(path)``, the file's own physics; with ``edit``, MuJoCo's compile of the file's
    ``MjSpec`` after ``edit(spec)`` (the rough tasks' generated ground added to it)."""
    import mujoco  # noqa: PLC0415

    if not os.path.isfile(path):
        raise FileNotFoundError(f"scene file {path} does not exist: pass scene_file= the path of an MJCF file")
    if edit is None:
        return CompiledModel(mujoco.MjModel.from_xml_path(path), path)
    spec = mujoco.MjSpec.from_file(path)
    edit(spec)
    return CompiledModel(spec.compile(), path)
