"""Gymnasium's MuJoCo model files, compiled by MuJoCo itself: the model the suite's tasks simulate.

The files are read from the installed gymnasium (``gymnasium/envs/mujoco/assets``), never copied,
and compiled by ``mujoco.MjModel.from_xml_path``, the same call Gymnasium's envs make. What MuJoCo
Warp cannot run is replaced here, in one place, and recorded (``CompiledModel.substitutions``):

* the PGS constraint solver (humanoid.xml, humanoidstandup.xml) becomes MuJoCo's Newton solver,
  with the file's iteration caps: both solve the same convex problem, PGS by projected Gauss-Seidel
  sweeps that stop after ``iterations`` (50) whether or not they converged, Newton to tolerance.
  docs/tasks.md ("Gymnasium's MuJoCo suite") measures what it changes.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field

import numpy as np

# The model fields that make two compiles of one file the same physics (tests/test_suite.py
# compares them between MuJoCo's model and the one MuJoCo Warp simulates).
PHYSICS_FIELDS = (
    "opt.timestep", "opt.integrator", "opt.cone", "opt.impratio", "opt.gravity", "opt.viscosity", "opt.density",
    "opt.wind", "opt.tolerance", "opt.ls_tolerance", "opt.iterations", "opt.ls_iterations",
    "opt.disableflags", "opt.enableflags",
    "body_mass", "body_inertia", "body_ipos", "body_iquat", "body_pos", "body_quat", "body_parentid",
    "jnt_type", "jnt_range", "jnt_limited", "jnt_stiffness", "jnt_solref", "jnt_solimp", "jnt_margin", "qpos0",
    "dof_damping", "dof_armature", "dof_frictionloss", "dof_solref", "dof_solimp",
    "actuator_gear", "actuator_ctrlrange", "actuator_ctrllimited", "actuator_forcerange",
    "actuator_gainprm", "actuator_biasprm", "actuator_gaintype", "actuator_biastype", "actuator_trntype",
    "actuator_trnid", "actuator_dyntype",
    "geom_type", "geom_size", "geom_pos", "geom_quat", "geom_friction", "geom_solref", "geom_solimp",
    "geom_solmix", "geom_margin", "geom_gap", "geom_condim", "geom_contype", "geom_conaffinity",
    "geom_priority", "geom_bodyid",
)


class GymnasiumAssetsMissing(FileNotFoundError):
    pass


def assets_dir() -> str:
    """Where the installed gymnasium keeps its MuJoCo model files."""
    try:
        import gymnasium  # noqa: PLC0415
    except ImportError as e:
        raise GymnasiumAssetsMissing("gymnasium is not installed: pip install 'gymnasium>=1.2.2'") from e
    folder = os.path.join(os.path.dirname(gymnasium.__file__), "envs", "mujoco", "assets")
    if not os.path.isdir(folder):
        raise GymnasiumAssetsMissing(
            f"gymnasium {gymnasium.__version__} at {os.path.dirname(gymnasium.__file__)} has no MuJoCo model files "
            f"({folder} is missing): pip install --force-reinstall 'gymnasium[mujoco]>=1.2.2'")
    return folder


def asset_path(xml_file: str) -> str:
    """A model file: a name in gymnasium's assets (Gymnasium's default ``xml_file``) or a path to one."""
    path = xml_file if os.path.isabs(xml_file) or os.sep in xml_file else os.path.join(assets_dir(), xml_file)
    if not os.path.isfile(path):
        known = sorted(f for f in os.listdir(assets_dir()) if f.endswith(".xml"))
        raise GymnasiumAssetsMissing(f"xml_file={xml_file!r}: no such model file ({path}); gymnasium ships {known}")
    return path


@dataclass
class CompiledModel:
    mjm: object  # mujoco.MjModel, as MuJoCo compiled the file, after the substitutions below
    path: str
    substitutions: list[str] = field(default_factory=list)  # what was changed for MuJoCo Warp, and why


def compile_model(xml_file: str) -> CompiledModel:
    import mujoco  # noqa: PLC0415

    path = asset_path(xml_file)
    mjm = mujoco.MjModel.from_xml_path(path)
    out = CompiledModel(mjm, path)
    if mjm.opt.solver == mujoco.mjtSolver.mjSOL_PGS:
        mjm.opt.solver = mujoco.mjtSolver.mjSOL_NEWTON
        out.substitutions.append("solver PGS -> Newton (MuJoCo Warp has no PGS solver)")
    return out


def field_value(mjm, name: str) -> np.ndarray:
    obj = mjm
    for part in name.split("."):
        obj = getattr(obj, part)
    return np.asarray(obj)


def model_differences(mjm, other, fields=PHYSICS_FIELDS, rtol: float = 1e-6) -> dict[str, float]:
    """The fields in which two MuJoCo models differ, with the largest relative difference of each."""
    diffs = {}
    for name in fields:
        a, b = field_value(mjm, name).astype(np.float64), field_value(other, name).astype(np.float64)
        if a.shape != b.shape:
            diffs[name] = float("inf")
            continue
        both_inf = np.isinf(a) & np.isinf(b) & (np.sign(a) == np.sign(b))
        gap = np.where(both_inf, 0.0, np.abs(a - b) / np.maximum(1.0, np.abs(a)))
        if gap.size and float(gap.max()) > rtol:
            diffs[name] = float(gap.max())
    return diffs
