"""The numbers of a locomotion task, in one place. Kernels receive them as a ``LocomotionParams``; a task's own
terms beside Isaac Gym's reward (``rewards``, ``terminations``: tables of ``warpgym.tasks.terms``, empty in the Ant
and the Humanoid) run in the same step."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, replace

import warp as wp

from kernels.robots.params import LocomotionParams
from warpgym.sim.physics import Physics
from warpgym.tasks.terms import Terms, changed_own_tables, validate_own_tables


@dataclass(frozen=True)
class LocomotionTask:
    name: str
    robot: str
    episode_length: int = 1000  # control steps; reaching it truncates
    dt: float = 1.0 / 60.0  # control step [s]
    substeps: int = 2
    physics: Physics = field(default_factory=Physics)  # integrator, iterations, armature, ...
    target: tuple[float, float, float] = (1000.0, 0.0, 0.0)
    power_scale: float = 1.0
    angular_velocity_scale: float = 1.0
    dof_velocity_scale: float = 0.2
    dof_force_scale: float = 0.0  # 0: joint forces are not observed
    contact_force_scale: float = 0.1
    heading_weight: float = 0.5
    up_weight: float = 0.1
    alive_reward: float = 0.5
    actions_cost: float = 0.005
    energy_cost: float = 0.05
    joints_at_limit_cost: float = 0.1
    joint_limit_threshold: float = 0.99
    scaled_limit_cost: bool = False
    death_cost: float = -2.0
    termination_height: float = 0.31
    dof_pos_noise: float = 0.2  # reset: dof position = default + U(-noise, noise), clamped to limits
    dof_vel_noise: float = 0.1  # reset: dof velocity = U(-noise, noise)
    # Any root or joint speed above this [m/s or rad/s] is a solver blow-up, not locomotion: the env
    # ends the episode with zero reward and flags it in info["diverged"].
    max_speed: float = 200.0
    # the task's own reward terms (each ``weight * value`` a step, added to Isaac Gym's reward, replaced by the death
    # cost as it is, and reported as ``info["reward_<name>"]``) and terminations (beside the fall, without the death
    # cost), over ``kernels.robots.buffers.RobotState``
    rewards: Terms = Terms("reward")
    terminations: Terms = Terms("termination")

    @property
    def observe_dof_forces(self) -> bool:
        return self.dof_force_scale != 0.0

    @property
    def forward_direction(self) -> tuple[float, float, float]:
        """Unit horizontal vector from the start (above the env's origin) towards the target."""
        x, y = self.target[0], self.target[1]
        norm = math.hypot(x, y)
        if norm == 0.0:
            raise ValueError(f"target={self.target!r} lies straight above the start: it gives no forward direction")
        return (x / norm, y / norm, 0.0)

    def forward_speed(self, travel, steps):
        """The forward speed [m/s] of a robot whose root moved by ``travel`` (..., 3: end minus start
        position) in ``steps`` control steps: the distance along ``forward_direction`` over the time.

        Every reporter uses this definition: the env's ``info["episode"]["s"]`` (its kernel twin,
        ``kernels.robots.observations.forward_speed``), evaluations, training rows, play.py's episodes and
        clips, and sim2sim.py in both simulators. Works on numpy arrays and torch tensors."""
        d = self.forward_direction
        return (travel[..., 0] * d[0] + travel[..., 1] * d[1]) / (steps * self.dt)

    def observation_size(self, num_dofs: int, num_feet: int) -> int:
        per_dof = 4 if self.observe_dof_forces else 3
        return 12 + per_dof * num_dofs + 6 * num_feet

    def replace(self, **changes) -> LocomotionTask:
        """A copy with these fields changed; ``physics`` may be a dict of the settings to change; ``rewards`` and
        ``terminations`` take the changes of the terms they name (``warpgym.tasks.terms.Terms.changed``)."""
        values = {name: getattr(self, name) for name in self.__dataclass_fields__}
        unknown = sorted(set(changes) - set(values))
        if unknown:
            raise ValueError(f"unknown task setting(s) {unknown}: choose from {sorted(values)}")
        changes = changed_own_tables(self, changes)
        physics = changes.pop("physics", None)
        if isinstance(physics, dict):
            physics = self.physics.replace(**physics)
        values.update(changes)
        if physics is not None:
            values["physics"] = physics
        return LocomotionTask(**values)

    def to_dict(self) -> dict:
        """The fields, the physics as a dict; the tables of terms as they are (their functions are code)."""
        plain = asdict(replace(self, rewards=Terms("reward"), terminations=Terms("termination")))
        return {**plain, "rewards": self.rewards, "terminations": self.terminations}

    def validate(self) -> None:
        if not isinstance(self.episode_length, int) or self.episode_length < 1:
            raise ValueError(f"episode_length={self.episode_length!r} must be a positive integer, e.g. 1000")
        if not (self.dt > 0):
            raise ValueError(f"dt={self.dt!r} must be positive, e.g. 1/60")
        if isinstance(self.substeps, bool) or not isinstance(self.substeps, int) or self.substeps < 1:
            raise ValueError(f"substeps={self.substeps!r} must be a positive integer, e.g. 2")
        if not (0.0 < self.joint_limit_threshold < 1.0):
            raise ValueError(f"joint_limit_threshold={self.joint_limit_threshold!r} must lie in (0, 1)")
        validate_own_tables(self)

    def own_terms(self) -> tuple[str, ...]:
        """The info keys of the task's own reward terms, in its table's order."""
        return tuple(f"reward_{name}" for name in self.rewards)

    def to_warp(self, start_height: float) -> LocomotionParams:
        """The kernels' view of this task: every field the struct shares with it, plus the start pose."""
        p = LocomotionParams()
        for name in LocomotionParams.vars:
            if name in self.__dataclass_fields__:
                value = getattr(self, name)
                setattr(p, name, int(value) if isinstance(value, bool) else value)
        p.target = wp.vec3(*self.target)
        p.start_pos = wp.vec3(0.0, 0.0, start_height)
        p.start_rot = wp.quat_identity()
        p.forward_dir = wp.vec3(*self.forward_direction)
        p.observe_dof_forces = int(self.observe_dof_forces)
        return p
