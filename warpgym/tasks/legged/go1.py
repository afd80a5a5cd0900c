"""Unitree Go1 following a velocity command, on flat ground (mjlab's ``Mjlab-Velocity-Flat-Unitree-Go1``,
``unitree_go1_flat_env_cfg``) and on rough ground (``Mjlab-Velocity-Rough-Unitree-Go1``), mjlab 1.6.0.

The Go1 of MuJoCo Menagerie as mjlab's asset zoo configures it (every collision geom on, the feet with condim 6
and their own friction, position actuators of 10 Hz and damping ratio 2, elliptic friction cones), its foot
friction randomised per axis, the trunk's centre of mass offset.
"""

import os
from dataclasses import dataclass, replace

from kernels.legged import events as ev
from kernels.legged import terminations as ends
from warpgym.tasks.legged.base import CRITIC_OBS, EVENTS, POLICY_OBS, REWARDS, TERMINATIONS, LeggedTask, with_height_scan
from warpgym.tasks.legged.robot_file import Actuator, Collision, RobotFile, Touch
from warpgym.tasks.legged.scan import GO1_FOOT_SCAN, TERRAIN_SCAN
from warpgym.tasks.legged.terrain import ROUGH
from warpgym.tasks.terms import Event, PerJoint, Termination, Terms

# mjlab's rough tasks build its ROUGH_TERRAINS_CFG in curriculum mode: one kind a column, ten levels
ROUGH_CURRICULUM = replace(ROUGH, curriculum=True)

FEET = ("FR", "FL", "RR", "RL")
HIP_THIGH = r".*(FR|FL|RR|RL)_(hip|thigh)_joint.*"
CALF = r".*(FR|FL|RR|RL)_calf_joint.*"


def _friction(axis: int, low: float, high: float, log_uniform: int) -> Event:
    return Event(ev.randomize_foot_friction, "startup", {"axis": axis, "value": (low, high), "log_uniform": log_uniform})


# condim-6 feet: sliding, torsional and rolling friction each drawn (mjlab's foot_friction_slide, _spin, _roll), in
# the place of the base's one axis
GO1_EVENTS = Terms("event", [
    *((n, EVENTS[n]) for n in ("reset_base", "reset_robot_joints", "push_robot")),
    ("foot_friction_slide", _friction(0, 0.3, 1.5, 0)), ("foot_friction_spin", _friction(1, 1e-4, 2e-2, 1)),
    ("foot_friction_roll", _friction(2, 1e-5, 5e-3, 1)),
    *((n, EVENTS[n]) for n in ("base_com", "encoder_bias"))])


# ---------------------------------------------------------------------------------------------------------------
# the Go1 from its own MJCF file (assets/unitree_go1.xml: mjlab's asset zoo's unitree_go1/xmls/go1.xml) and the
# numbers of mjlab's go1_constants.py: the tasks build their scenes from them (tests/test_robot_file.py compares
# them with go1_velocity_flat.xml and go1_velocity_rough.xml, exported from mjlab's env)

GO1_ROTOR_INERTIA = 0.000111842  # [kg m^2], Unitree's URDF
GO1_FOOT = "^[FR][LR]_foot_collision$"
GO1_PHYSICS = {"cone": "elliptic", "impratio": 10.0}  # the Go1's tasks' changes to mjlab's options
GO1_POSTURE = {"standing": {HIP_THIGH: 0.05, CALF: 0.1}, "walking": {HIP_THIGH: 0.3, CALF: 0.6},
               "running": {HIP_THIGH: 0.3, CALF: 0.6}}


def go1_robot_file(file: str | None = None) -> RobotFile:
    """The Go1's definition; ``file``: its MJCF (default: the one beside the tasks' scenes)."""
    def motor(joints, gear, effort):
        return Actuator(joints, effort, GO1_ROTOR_INERTIA * gear * gear, natural_frequency=10.0, damping_ratio=2.0)

    return RobotFile(
        file or os.path.join(os.path.dirname(__file__), "assets", "unitree_go1.xml"), root="trunk", name="Unitree Go1",
        feet=tuple(f"{f}_foot_collision" for f in FEET), foot_sites=FEET, base_height=0.278,
        joint_pos={".*thigh_joint": 0.9, ".*calf_joint": -1.8, ".*R_hip_joint": 0.1, ".*L_hip_joint": -0.1},
        actuators=(motor((".*_hip_joint", ".*_thigh_joint"), 6.0, 23.7), motor(".*_calf_joint", 9.0, 35.55)),
        collision=Collision((r".*_collision\d*",), contype=1, conaffinity=1,
                            condim={GO1_FOOT: 6, r".*_collision\d*": 1}, priority={GO1_FOOT: 1, ".*": 0},
                            friction={GO1_FOOT: (1.0, 5e-3, 5e-4)}, solref=(0.01, 1.0)),
        # the rough task's contact sensors beyond the feet's, in mjlab's order (its unitree_go1_rough_env_cfg)
        touches=(Touch("illegal", (r"[FR][LR]_thigh_collision\d",), name="thigh_ground_touch"),
                 Touch("shank", (r"[FR][LR]_calf_collision\d",)), Touch("trunk", ("trunk_collision", "head_collision"))),
        posture=GO1_POSTURE, physics=GO1_PHYSICS, self_collisions=True)


GO1 = go1_robot_file()
GO1_ROUGH_TOUCHES = tuple((t.sensor, t.geoms) for t in GO1.touches)


@dataclass(frozen=True)
class Go1VelocityFlat(LeggedTask):
    name: str = "Go1VelocityFlat-v0"
    mirrors: str = "Mjlab-Velocity-Flat-Unitree-Go1"
    scene_file: str = ""
    robot: object = GO1
    root_body: str = "robot/trunk"
    upright_body: str = "robot/trunk"
    angvel_body: str = "robot/trunk"
    com_body: str = "robot/trunk"
    foot_geoms: tuple = tuple(f"robot/{f}_foot_collision" for f in FEET)
    foot_sites: tuple = tuple(f"robot/{f}" for f in FEET)
    foot_sensors: tuple = tuple(f"feet_ground_contact_{f}_foot_collision" for f in FEET)
    nconmax: int = 32
    rewards: object = REWARDS.changed({"pose": {"params": {
        "std_standing": PerJoint(((HIP_THIGH, 0.05), (CALF, 0.1))),
        "std_walking": PerJoint(((HIP_THIGH, 0.3), (CALF, 0.6))),
        "std_running": PerJoint(((HIP_THIGH, 0.3), (CALF, 0.6)))}}}, "Go1VelocityFlat-v0: rewards")
    events: object = GO1_EVENTS


@dataclass(frozen=True)
class Go1VelocityRough(Go1VelocityFlat):
    """Unitree Go1 on mjlab's rough ground: ``Mjlab-Velocity-Rough-Unitree-Go1`` (``unitree_go1_rough_env_cfg``).

    What the flat task takes away comes back: the generated ground with its curriculum, the height scan under the
    trunk in both observations, the feet's scanned heights, upright measured against the ground's slope, the
    calves', trunk's and head's touches of the ground and self-collisions charged, the thighs' touch ending an
    episode where tilt no longer does, and more room for contacts.
    """

    name: str = "Go1VelocityRough-v0"
    mirrors: str = "Mjlab-Velocity-Rough-Unitree-Go1"
    physics: tuple = (("ccd_iterations", 500),)
    self_collision_sensor: str = "self_collision_trunk"
    shank_sensors: tuple = tuple(f"shank_ground_touch_{f}_calf_collision{i}" for f in FEET for i in (1, 2))
    trunk_sensors: tuple = ("trunk_ground_touch_trunk_collision", "trunk_ground_touch_head_collision")
    illegal_contact_sensors: tuple = tuple(f"thigh_ground_touch_{f}_thigh_collision{i}" for f in FEET for i in (1, 2, 3))
    rewards: object = Go1VelocityFlat.rewards.changed({
        "self_collisions": -0.1, "shank_collision": -0.1, "trunk_head_collision": -0.1,
        "upright": {"params": {"on_terrain": 1}}}, "Go1VelocityRough-v0: rewards")
    policy_obs: object = with_height_scan(POLICY_OBS, TERRAIN_SCAN.max_distance, noise=0.1)
    critic_obs: object = with_height_scan(CRITIC_OBS, TERRAIN_SCAN.max_distance, noise=0.0)
    # a thigh's touch ends an episode where tilt no longer does
    terminations: object = TERMINATIONS.changed({
        "fell_over": None, "illegal_contact": Termination(ends.illegal_contact),
        "out_of_terrain_bounds": Termination(ends.out_of_terrain_bounds, time_out=True)},
        "Go1VelocityRough-v0: terminations")
    nconmax: int = 35
    njmax: int = 1500
    contact_sensor_maxmatch: int = 500
    terrain: object = ROUGH_CURRICULUM
    height_scan: object = TERRAIN_SCAN
    foot_scan: object = GO1_FOOT_SCAN
