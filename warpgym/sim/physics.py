"""The physics settings a robot is simulated with, beyond its MJCF: one definition that ``Sim``, the
native MuJoCo twin (``warpgym.native.robots``) and ``warpgym train --physics`` share.

docs/history.md ("Physics settings: the investigation") says which values were tried and why the defaults are what
they are.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

import numpy as np

INTEGRATORS = ("euler", "implicitfast", "implicit")


@dataclass(frozen=True)
class Physics:
    """Physics settings applied on top of the robot's MJCF.

    integrator: MuJoCo's integrator; "implicitfast" (Newton's default) treats joint damping implicitly.
    solver_iterations, ls_iterations: caps on MuJoCo's Newton-solver and line-search iterations per substep.
    armature: rotor inertia added to every hinge [kg m^2]; None keeps the MJCF's.
    max_joint_speed: hinge speeds are clamped to this after every substep [rad/s], as PhysX clamps
        articulation joint velocities; None: no clamp.
    contact_timeconst: MuJoCo ``solref`` time constant of every contact [s] (stiffer when smaller);
        None keeps the MJCF's (0.02 s unless a geom sets it).
    motor_speed: the no-load speed of every motor [rad/s]: a DC motor's back-EMF, which takes
        gear / motor_speed of torque per rad/s from its command (joint damping: at the full command the
        torque falls to 0 at this speed; the gear at power_scale 1). None: ideal torque sources, as the
        MJCF's motors.
    exact_damping: scale each hinge's damping for the substep so that the implicit integrator slows
        a damped joint per step as the continuous model does (``exact_damping_scale``); False keeps
        the MJCF's damping, which implicit Euler applies more weakly the coarser the step.
    """

    integrator: str = "implicitfast"
    solver_iterations: int = 8
    ls_iterations: int = 8
    armature: float | None = None
    max_joint_speed: float | None = None
    contact_timeconst: float | None = None
    motor_speed: float | None = None
    exact_damping: bool = False

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator={self.integrator!r}: choose one of {list(INTEGRATORS)}")
        for name in ("solver_iterations", "ls_iterations"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name}={v!r} must be a positive integer, e.g. 8")
        for name, example in (("armature", "0.05"), ("max_joint_speed", "40"), ("contact_timeconst", "0.02"),
                              ("motor_speed", "25")):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name}={v!r} must be a positive number (e.g. {example}) or None")
        if not isinstance(self.exact_damping, bool):
            raise ValueError(f"exact_damping={self.exact_damping!r} must be true or false")

    @classmethod
    def from_dict(cls, values: dict | None) -> Physics:
        values = dict(values or {})
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(values) - names)
        if unknown:
            raise ValueError(f"unknown physics setting(s) {unknown}: choose from {sorted(names)}")
        return cls(**values)

    def replace(self, **changes) -> Physics:
        return Physics.from_dict({**asdict(self), **changes})

    def to_dict(self) -> dict:
        return asdict(self)


def recorded(values: dict | None) -> dict:
    """The physics a run or checkpoint recorded, complete: it was written whole (``to_dict``), so a setting
    added since then takes ``Physics``'s own default (off), not the task's default of today, which would
    replay an old policy on physics it never saw. ``{}`` or None (nothing recorded): ``{}``, the task's."""
    return Physics.from_dict(values).to_dict() if values else {}


def parse_setting(text: str) -> tuple[str, object]:
    """``"armature=0.05"`` -> ("armature", 0.05); ``none`` -> None; for ``--physics`` flags."""
    if "=" not in text:
        raise ValueError(f"{text!r}: write NAME=VALUE, e.g. armature=0.05")
    name, raw = (s.strip() for s in text.split("=", 1))
    if raw.lower() == "none":
        return name, None
    if raw.lower() in ("true", "false"):
        return name, raw.lower() == "true"
    for convert in (int, float):
        try:
            return name, convert(raw)
        except ValueError:
            pass
    return name, raw


def hinge_inverse_inertia(mujoco, model) -> tuple[np.ndarray, np.ndarray]:
    """The hinge dofs of a MuJoCo ``model`` and, for each, (M^-1)_ii at the start pose (hinges at 0
    clamped into their ranges): one over the joint's effective inertia I with every other joint and
    the floating base free to move. Takes the ``mujoco`` module so that this file imports neither it
    nor Warp."""
    hinges = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE)
    dofs = model.jnt_dofadr[hinges]
    data = mujoco.MjData(model)
    data.qpos[:] = model.qpos0
    for j in hinges:
        lo, hi = model.jnt_range[j] if model.jnt_limited[j] else (-np.inf, np.inf)
        data.qpos[model.jnt_qposadr[j]] = np.clip(0.0, lo, hi)
    mujoco.mj_forward(model, data)
    unit, column = np.zeros((1, model.nv)), np.zeros((1, model.nv))
    inverse = np.empty(len(dofs))
    for k, dof in enumerate(dofs):
        unit[:] = 0.0
        unit[0, dof] = 1.0
        mujoco.mj_solveM(model, data, column, unit)
        inverse[k] = column[0, dof]
    return dofs, inverse


def exact_damping_scale(mujoco, model, timestep: float) -> tuple[np.ndarray, np.ndarray]:
    """The hinge dofs of a MuJoCo ``model`` and the factor on each one's damping that makes implicit
    Euler exact for it at ``timestep``.

    A step h of implicit Euler keeps 1 / (1 + h d / I) of a damped joint's speed, the continuous
    model exp(-h d / I) (I: the effective inertia of ``hinge_inverse_inertia``). With d scaled by
    (e^x - 1) / x, x = h d / I, the two agree, so the damping a policy meets does not depend on the
    step; at the Humanoid's 1/180 s the factors are 1.06-1.84 (docs/history.md, "Physics settings: the
    investigation")."""
    dofs, inverse = hinge_inverse_inertia(mujoco, model)
    x = timestep * model.dof_damping[dofs] * inverse
    return dofs, np.where(x > 0, np.expm1(x) / np.where(x > 0, x, 1.0), 1.0)


def motor_damping(gears: np.ndarray, motor_speed: float | None) -> np.ndarray:
    """Each motor's back-EMF as joint damping [N m s/rad]: gear / motor_speed (0 without a motor
    model), so a joint driven at the full command stops accelerating at ``motor_speed``."""
    gears = np.asarray(gears, np.float64)
    return gears / motor_speed if motor_speed is not None else np.zeros_like(gears)
