"""The physics settings a robot is simulated with, beyond its MJCF: one definition that ``Sim``, the
native MuJoCo twin (``warpgym.native``) and ``warpgym train --physics`` share.

docs/tasks.md ("Physics settings") says which values were tried and why the defaults are what
they are.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

INTEGRATORS = ("euler", "implicitfast")


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
    """

    integrator: str = "implicitfast"
    solver_iterations: int = 8
    ls_iterations: int = 8
    armature: float | None = None
    max_joint_speed: float | None = None
    contact_timeconst: float | None = None

    def __post_init__(self):
        if self.integrator not in INTEGRATORS:
            raise ValueError(f"integrator={self.integrator!r}: choose one of {list(INTEGRATORS)}")
        for name in ("solver_iterations", "ls_iterations"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{name}={v!r} must be a positive integer, e.g. 8")
        for name, example in (("armature", "0.05"), ("max_joint_speed", "40"), ("contact_timeconst", "0.02")):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ValueError(f"{name}={v!r} must be a positive number (e.g. {example}) or None")

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


def parse_setting(text: str) -> tuple[str, object]:
    """``"armature=0.05"`` -> ("armature", 0.05); ``none`` -> None; for ``--physics`` flags."""
    if "=" not in text:
        raise ValueError(f"{text!r}: write NAME=VALUE, e.g. armature=0.05")
    name, raw = (s.strip() for s in text.split("=", 1))
    if raw.lower() == "none":
        return name, None
    for convert in (int, float):
        try:
            return name, convert(raw)
        except ValueError:
            pass
    return name, raw
