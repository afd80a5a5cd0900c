"""What the legged robots' velocity tasks share (mjlab's ``make_velocity_env_cfg`` and its flat-ground edits): the
command and the tables of terms (rewards, the policy's and the critic's observations, terminations and events:
resets, pushes and the randomisation drawn when an env is built; each term a Warp function of ``kernels/legged``
with its weight, noise or schedule and its parameters, ``warpgym.tasks.terms``). Each robot's file beside this one
names its parts in its scene and sets what its mjlab config sets for it.

Every field is a constructor keyword of the env (``gym.make_vec("warpgym/Go1VelocityFlat-v0", num_envs=4096,
lin_vel_x=(-2.0, 2.0), rewards={"foot_slip": -0.2}, events={"push_robot": None})``); ``replace`` checks a change and
``validate`` the whole.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, fields, replace
from typing import ClassVar

from kernels.legged import events as ev
from kernels.legged import observations as obs
from kernels.legged import rewards as rew
from kernels.legged import terminations as ends
from kernels.legged.params import SELF_COLLISION, SHANK_GROUND, TRUNK_GROUND
from warpgym.tasks.terms import Dims, Event, Observation, PerJoint, Reward, Termination, Terms
from warpgym.tasks.terms import validate as validate_terms

ASSETS = os.path.join(os.path.dirname(os.path.abspath(__file__)), "assets")
TABLES = ("rewards", "policy_obs", "critic_obs", "terminations", "events")  # a task's tables of terms

# mjlab's reward terms of the velocity tasks (make_velocity_env_cfg), in its config's order, before a robot's config
# changes them (0: the term is off); the posture's stds per joint are the robot's
REWARDS = Terms("reward", {
    "track_linear_velocity": Reward(rew.track_linear_velocity, 2.0, {"std": math.sqrt(0.25)}),
    "track_angular_velocity": Reward(rew.track_angular_velocity, 2.0, {"std": math.sqrt(0.5)}),
    "upright": Reward(rew.upright, 1.0, {"std": math.sqrt(0.2), "on_terrain": 0}),
    "pose": Reward(rew.pose, 1.0, {"std_standing": PerJoint(()), "std_walking": PerJoint(()),
                                   "std_running": PerJoint(()), "walking_threshold": 0.05, "running_threshold": 1.5}),
    "body_ang_vel": Reward(rew.body_ang_vel, 0.0),
    "angular_momentum": Reward(rew.angular_momentum, 0.0),
    "dof_pos_limits": Reward(rew.dof_pos_limits, -1.0),
    "action_rate_l2": Reward(rew.action_rate_l2, -0.1),
    "air_time": Reward(rew.air_time, 0.0, {"threshold_min": 0.05, "threshold_max": 0.5, "command_threshold": 0.5}),
    "foot_clearance": Reward(rew.foot_clearance, -2.0, {"target_height": 0.1, "command_threshold": 0.05}),
    "foot_swing_height": Reward(rew.foot_swing_height, -0.25, {"target_height": 0.1, "command_threshold": 0.05}),
    "foot_slip": Reward(rew.foot_slip, -0.1, {"command_threshold": 0.05}),
    "soft_landing": Reward(rew.soft_landing, -1e-5, {"command_threshold": 0.05}),
    "self_collisions": Reward(rew.contact_steps, 0.0, {"group": SELF_COLLISION}),
    "shank_collision": Reward(rew.contact_steps, 0.0, {"group": SHANK_GROUND}),  # the rough Go1's calves on the ground
    "trunk_head_collision": Reward(rew.contact_steps, 0.0, {"group": TRUNK_GROUND}),  # ... its trunk or head
})


def _joints(d: Dims) -> int:
    return d.joints


def _actions(d: Dims) -> int:
    return d.actions


def _feet(d: Dims) -> int:
    return d.feet


def _forces(d: Dims) -> int:
    return 3 * d.feet


def _scan(d: Dims) -> int:
    if not d.scan:
        raise ValueError("the height_scan observation needs the task's height_scan pattern: pass height_scan=")
    return d.scan


# mjlab's "actor" group: the policy's observation, with uniform noise on its first five terms
POLICY_OBS = Terms("observation", {
    "base_lin_vel": Observation(obs.base_lin_vel, 3, noise=0.5),
    "base_ang_vel": Observation(obs.base_ang_vel, 3, noise=0.2),
    "projected_gravity": Observation(obs.gravity, 3, noise=0.05),
    "joint_pos": Observation(obs.joint_pos, _joints, noise=0.01, params={"biased": 1}),
    "joint_vel": Observation(obs.joint_vel, _joints, noise=1.5),
    "actions": Observation(obs.last_action, _actions),
    "command": Observation(obs.velocity_command, 3),
})
# mjlab's "critic" group: the actor's terms without noise or encoder bias, and the feet's state
CRITIC_OBS = Terms("observation", {
    **{name: replace(term, noise=0.0) for name, term in POLICY_OBS.items()},
    "joint_pos": Observation(obs.joint_pos, _joints, params={"biased": 0}),
    "foot_height": Observation(obs.feet_height, _feet),
    "foot_air_time": Observation(obs.feet_air_time, _feet),
    "foot_contact": Observation(obs.feet_contact, _feet),
    "foot_contact_forces": Observation(obs.feet_contact_forces, _forces),
})
# the rough tasks' height scan, both groups (the policy's with noise), after the command; mjlab scales it by
# 1 / the scan's reach
HEIGHT_SCAN = Observation(obs.height_scan, _scan)

TERMINATIONS = Terms("termination", {
    "fell_over": Termination(ends.bad_orientation, params={"limit_angle": math.radians(70.0)}),
})


# mjlab's events (make_velocity_env_cfg), by its names: the reset pose, a push every 1-3 s, and the startup
# randomisation of the feet's friction, the base's centre of mass and the encoders' bias
EVENTS = Terms("event", {
    "reset_base": Event(ev.reset_root_pose, "reset", {"x": (-0.5, 0.5), "y": (-0.5, 0.5), "z": (0.01, 0.05),
                                                      "yaw": (-3.14, 3.14)}),
    "reset_robot_joints": Event(ev.reset_joints_by_offset, "reset", {"position": (0.0, 0.0), "velocity": (0.0, 0.0)}),
    "push_robot": Event(ev.push_by_setting_velocity, "interval", {
        "x": (-0.5, 0.5), "y": (-0.5, 0.5), "z": (-0.4, 0.4), "roll": (-0.52, 0.52), "pitch": (-0.52, 0.52),
        "yaw": (-0.78, 0.78)}, interval=(1.0, 3.0)),
    "foot_friction": Event(ev.randomize_foot_friction, "startup", {"axis": 0, "value": (0.3, 1.2), "log_uniform": 0}),
    "base_com": Event(ev.randomize_com, "startup", {"x": (-0.025, 0.025), "y": (-0.025, 0.025), "z": (-0.03, 0.03)}),
    "encoder_bias": Event(ev.randomize_encoder_bias, "startup", {"bias": (-0.015, 0.015)}),
})


def with_height_scan(table: Terms, max_distance: float, noise: float) -> Terms:
    """``table`` with the height scan after the command (mjlab's place for it), scaled by 1 / its reach."""
    scan = replace(HEIGHT_SCAN, scale=1.0 / max_distance, noise=noise)
    items = []
    for name, term in table.items():
        items.append((name, term))
        if name == "command":
            items.append(("height_scan", scan))
    return Terms("observation", items)


@dataclass(frozen=True)
class LeggedTask:
    name: str
    mirrors: str  # the mjlab task this one mirrors
    # the scene: built from a robot's own file and definition (``robot``: a robot_file.RobotFile; a robot_task.robot
    # name, TOML definition or robot file through ``replace``) or, without one, an MJCF scene file (in
    # warpgym/tasks/legged/assets, or a path)
    scene_file: str
    # the robot's parts, by their names in the scene
    root_body: str
    upright_body: str  # whose tilt the upright reward scores
    angvel_body: str  # whose roll and pitch rates body_ang_vel charges
    com_body: str  # whose centre of mass is randomised
    foot_geoms: tuple[str, ...]  # whose friction is randomised
    foot_sites: tuple[str, ...]  # the feet's heights and velocities
    foot_sensors: tuple[str, ...]  # contact sensors "<name>_found" and "<name>_force", one per foot
    self_collision_sensor: str = ""  # "<name>_force" felt by self-collisions; "": none
    # more contact sensors ("<name>_force"), each group counted as mjlab's force history counts it: the calves'
    # and the trunk's and head's touches of the ground (terms), and those that end an episode (illegal contact)
    shank_sensors: tuple[str, ...] = ()
    trunk_sensors: tuple[str, ...] = ()
    illegal_contact_sensors: tuple[str, ...] = ()
    imu_lin_vel_sensor: str = "robot/imu_lin_vel"
    imu_ang_vel_sensor: str = "robot/imu_ang_vel"
    angmom_sensor: str = "robot/root_angmom"
    # action: a joint position target, action * scale + default position, the scale action_scale * effort
    # limit / stiffness of the joint's actuator (mjlab's GO1_ACTION_SCALE, G1_ACTION_SCALE)
    action_scale: float = 0.25
    soft_joint_limit_factor: float = 0.9
    decimation: int = 4
    episode_length_s: float = 20.0
    # MuJoCo Warp's contact and constraint room per world
    nconmax: int = 32
    njmax: int = 300
    contact_sensor_maxmatch: int = 64
    # velocity command
    lin_vel_x: tuple[float, float] = (-1.0, 1.0)
    lin_vel_y: tuple[float, float] = (-1.0, 1.0)
    ang_vel_z: tuple[float, float] = (-0.5, 0.5)
    heading: tuple[float, float] = (-math.pi, math.pi)
    resampling_time: tuple[float, float] = (3.0, 8.0)
    rel_standing_envs: float = 0.1
    rel_heading_envs: float = 0.3
    rel_forward_envs: float = 0.2
    heading_control_stiffness: float = 0.5
    # mjlab's command curriculum: from env step `step` on, the ranges given (None: unchanged) replace the earlier
    command_stages: tuple = ((5000 * 24, (-1.5, 2.0), None, (-0.7, 0.7)), (10000 * 24, (-2.0, 3.0), None, None))
    # the tables of terms (warpgym.tasks.terms): rewards, the policy's and the critic's observations (on rough ground
    # with the height scan), the terminations beside the time limit, the events; ``replace`` takes their changes
    rewards: Terms = REWARDS
    policy_obs: Terms = POLICY_OBS
    critic_obs: Terms = CRITIC_OBS
    terminations: Terms = TERMINATIONS
    events: Terms = EVENTS
    robot: object = None
    physics: tuple = ()  # ((option, value), ...): changes to the robot's MuJoCo options (robot_file.PHYSICS)
    # the force [N] above which a contact group's sensor counts a touch (mjlab's contact sensors' threshold)
    self_collision_force: float = 10.0
    # rough ground (terrain=None: the scene's floor): a TerrainGrid (warpgym.tasks.legged.terrain, curriculum=True)
    # generated from terrain_seed into the scene's "terrain" body; each world's first level drawn up to
    # max_init_terrain_level; an episode whose base leaves the ground (less terrain_margin) ends as a time-out
    terrain: object = None
    terrain_seed: int = 0
    max_init_terrain_level: int = 5
    terrain_margin: float = 0.3
    # ground scans (warpgym.tasks.legged.scan.ScanPattern): the height scan under the root body that both
    # observations see (the policy's with noise_height_scan), the ring under each foot site for the feet's heights
    height_scan: object = None
    foot_scan: object = None
    # the observation terms' noise (mjlab's play mode turns it off)
    observation_noise: bool = True

    # fields that describe the task rather than configure it
    OWN: ClassVar[tuple[str, ...]] = ("name", "mirrors")

    @property
    def episode_length(self) -> int:
        """Control steps to the time limit (mjlab: ceil(episode_length_s / step dt))."""
        return math.ceil(self.episode_length_s / (self.decimation * self.timestep))

    @property
    def timestep(self) -> float:
        return 0.005  # the scene's option (checked against the compiled model when an env is built)

    @property
    def scene_path(self) -> str:
        """The file the scene comes from: the robot's own (the scene built from it) or the scene file."""
        if self.robot is not None:
            return self.robot.file
        return self.scene_file if os.sep in self.scene_file else os.path.join(ASSETS, self.scene_file)

    def weights(self) -> dict[str, float]:
        return {name: term.weight for name, term in self.rewards.items()}

    # ------------------------------------------------------------------ keyword arguments
    @classmethod
    def argument_names(cls) -> list[str]:
        return [f.name for f in fields(cls) if f.name not in cls.OWN]

    def replace(self, **changes) -> LeggedTask:
        """A copy with constructor keywords changed; a table of terms (``rewards``, ``policy_obs``, ``critic_obs``,
        ``terminations``) takes the changes of the terms it names (``warpgym.tasks.terms.Terms.changed``)."""
        unknown = sorted(set(changes) - {f.name for f in fields(self)})
        if unknown:
            raise ValueError(f"{self.name} has no argument(s) {unknown}: it takes {self.argument_names()}")
        robot = changes.pop("robot", None)
        if robot is not None:  # the robot first: its parts and its own changes, then the caller's
            from warpgym.tasks.legged.robot_task import with_robot  # noqa: PLC0415

            return with_robot(self, robot).replace(**changes)
        for name in TABLES:
            if name in changes:
                changes[name] = getattr(self, name).changed(changes[name], f"{self.name}: {name}")
        for name, value in changes.items():
            if isinstance(getattr(self, name), tuple) and isinstance(value, list):
                changes[name] = tuple(tuple(v) if isinstance(v, list) else v for v in value)
        out = replace(self, **changes)
        out.validate()
        return out

    def validate(self) -> None:
        def fail(name, why):
            raise ValueError(f"{self.name}: {name}={getattr(self, name)!r} {why}")

        for name in ("lin_vel_x", "lin_vel_y", "ang_vel_z", "heading", "resampling_time"):
            if not _is_range(getattr(self, name)):
                fail(name, "must be a (low, high) pair of finite numbers with low <= high, e.g. (-1.0, 1.0)")
        if self.resampling_time[0] <= 0:
            fail("resampling_time", "must be positive seconds, e.g. (3.0, 8.0)")
        for name in ("decimation", "nconmax", "njmax", "contact_sensor_maxmatch"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                fail(name, "must be a positive integer")
        positive = ("episode_length_s", "action_scale", "soft_joint_limit_factor")
        non_negative = ("rel_standing_envs", "rel_heading_envs", "rel_forward_envs", "heading_control_stiffness",
                        "self_collision_force", "terrain_margin")
        for name in positive + non_negative:
            v = getattr(self, name)
            ok = _is_number(v) and (v > 0 if name in positive else v >= 0)
            if not ok:
                fail(name, "must be a positive number" if name in positive else "must be 0 or a positive number")
        for name in ("rel_standing_envs", "rel_heading_envs", "rel_forward_envs"):
            if getattr(self, name) > 1:
                fail(name, "is a share of the worlds, in [0, 1]")
        for name in TABLES:
            table = getattr(self, name)
            if not isinstance(table, Terms):
                fail(name, "must be a table of terms (warpgym.tasks.terms.Terms)")
            validate_terms(table, f"{self.name}: {name}")
        for stage in self.command_stages:
            if not (isinstance(stage, tuple) and len(stage) == 4 and isinstance(stage[0], int) and stage[0] >= 0
                    and all(r is None or _is_range(r) for r in stage[1:])):
                fail("command_stages", "must hold (step, lin_vel_x, lin_vel_y, ang_vel_z) with ranges or None")
        for name, event in self.events.items():
            if event.func is ev.randomize_foot_friction:
                p = dict(event.params)
                if p.get("axis") not in (0, 1, 2) or not _is_range(p.get("value")) or p["value"][0] <= 0:
                    raise ValueError(f"{self.name}: events[{name!r}] params={p!r}: axis must be 0 (sliding), 1 "
                                     "(torsional) or 2 (rolling) and value a (low, high) range with low > 0")
        if self.terrain is not None and not getattr(self.terrain, "curriculum", False):
            fail("terrain", "must be a TerrainGrid with curriculum=True (one kind a column, levels along rows), "
                            "e.g. dataclasses.replace(terrain.ROUGH, curriculum=True)")
        if isinstance(self.max_init_terrain_level, bool) or not isinstance(self.max_init_terrain_level, int) \
                or self.max_init_terrain_level < 0:
            fail("max_init_terrain_level", "must be a level >= 0 (mjlab's rough tasks: 5)")
        upright = self.rewards.get("upright")
        if upright is not None and dict(upright.params).get("on_terrain") and self.height_scan is None:
            raise ValueError(f"{self.name}: rewards['upright'] measures tilt against the ground (on_terrain=1), which "
                             "needs a height_scan to fit the ground's normal to")
        if self.robot is not None and not hasattr(self.robot, "feet"):
            fail("robot", "must be a robot's definition (robot_file.RobotFile): pass robot= a zoo name, a TOML "
                          "definition or a robot file through replace")
        if not (isinstance(self.physics, tuple) and all(isinstance(p, tuple) and len(p) == 2 for p in self.physics)):
            fail("physics", "must be ((option, value), ...) pairs, e.g. (('ccd_iterations', 500),)")
        if "illegal_contact" in self.terminations and not self.illegal_contact_sensors:
            raise ValueError(f"{self.name}: terminations['illegal_contact'] has no sensors to feel it: name them in "
                             "illegal_contact_sensors")

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _is_range(v) -> bool:
    return isinstance(v, tuple) and len(v) == 2 and all(_is_number(x) for x in v) and v[0] <= v[1]
