"""Unitree G1 (29 joints) following a velocity command, on flat ground (mjlab's ``Mjlab-Velocity-Flat-Unitree-G1``,
``unitree_g1_flat_env_cfg``) and on rough ground (``Mjlab-Velocity-Rough-Unitree-G1``), mjlab 1.6.0.

The G1 of MuJoCo Menagerie as mjlab's asset zoo configures it (every collision geom on, self-collisions
included, seven capsules a foot with condim 3), its knees-bent keyframe, the torso's centre of mass offset, a
penalty on the torso's roll and pitch rates, on the whole body's angular momentum and on self-collisions.
"""

import os
from dataclasses import dataclass

from kernels.legged import terminations as ends
from warpgym.tasks.legged.base import CRITIC_OBS, POLICY_OBS, REWARDS, TERMINATIONS, LeggedTask, with_height_scan
from warpgym.tasks.legged.go1 import ROUGH_CURRICULUM
from warpgym.tasks.legged.robot_file import Actuator, Collision, RobotFile
from warpgym.tasks.legged.scan import G1_FOOT_SCAN, TERRAIN_SCAN
from warpgym.tasks.terms import PerJoint, Termination

SIDES = ("left", "right")
# the posture's stds by joint; mjlab's rationale: knees and hip pitch loosest for the stride, hip roll and yaw tighter
# against sway, ankle roll tight for balance, the waist tight to keep the torso upright, the arms free to swing
WALKING = (
    (r".*hip_pitch.*", 0.3), (r".*hip_roll.*", 0.15), (r".*hip_yaw.*", 0.15), (r".*knee.*", 0.35),
    (r".*ankle_pitch.*", 0.25), (r".*ankle_roll.*", 0.1), (r".*waist_yaw.*", 0.2), (r".*waist_roll.*", 0.08),
    (r".*waist_pitch.*", 0.1), (r".*shoulder_pitch.*", 0.15), (r".*shoulder_roll.*", 0.15),
    (r".*shoulder_yaw.*", 0.1), (r".*elbow.*", 0.15), (r".*wrist.*", 0.3))
RUNNING = (
    (r".*hip_pitch.*", 0.5), (r".*hip_roll.*", 0.2), (r".*hip_yaw.*", 0.2), (r".*knee.*", 0.6),
    (r".*ankle_pitch.*", 0.35), (r".*ankle_roll.*", 0.15), (r".*waist_yaw.*", 0.3), (r".*waist_roll.*", 0.08),
    (r".*waist_pitch.*", 0.2), (r".*shoulder_pitch.*", 0.5), (r".*shoulder_roll.*", 0.2),
    (r".*shoulder_yaw.*", 0.15), (r".*elbow.*", 0.35), (r".*wrist.*", 0.3))


# ---------------------------------------------------------------------------------------------------------------
# the G1 from its own MJCF file (assets/unitree_g1.xml: mjlab's asset zoo's unitree_g1/xmls/g1.xml) and the numbers
# of mjlab's g1_constants.py: the tasks build their scenes from them (tests/test_robot_file.py compares them
# with g1_velocity_flat.xml and g1_velocity_rough.xml, exported from mjlab's env)


def two_stage_planetary(rotor: tuple[float, float, float], gears: tuple[float, float, float]) -> float:
    """The reflected inertia [kg m^2] of a motor behind a two-stage planetary gearbox: each stage's rotor inertia times
    the square of the reduction after it (``gears[0]`` is the motor's own, 1)."""
    return rotor[0] * (gears[1] * gears[2]) ** 2 + rotor[1] * gears[2] ** 2 + rotor[2]


# Unitree's motors: (rotor inertias, stage reductions, effort limit [N m])
G1_MOTORS = {
    "5020": ((0.139e-4, 0.017e-4, 0.169e-4), (1.0, 1 + 46 / 18, 1 + 56 / 16), 25.0),
    "7520_14": ((0.489e-4, 0.098e-4, 0.533e-4), (1.0, 4.5, 1 + 48 / 22), 88.0),
    "7520_22": ((0.489e-4, 0.109e-4, 0.738e-4), (1.0, 4.5, 5.0), 139.0),
    "4010": ((0.068e-4, 0.0, 0.0), (1.0, 5.0, 5.0), 5.0),
}
G1_FOOT = r"^(left|right)_foot[1-7]_collision$"


def g1_robot_file(file: str | None = None) -> RobotFile:
    """The G1's definition; ``file``: its MJCF (default: the one beside the tasks' scenes)."""
    def motor(joints, kind, pair=1):  # the waist's pitch and roll and each ankle: two motors on one joint
        rotor, gears, effort = G1_MOTORS[kind]
        return Actuator(joints, pair * effort, pair * two_stage_planetary(rotor, gears), natural_frequency=10.0,
                        damping_ratio=2.0)

    return RobotFile(
        file or os.path.join(os.path.dirname(__file__), "assets", "unitree_g1.xml"), root="pelvis", name="Unitree G1",
        torso="torso_link", feet=("left_ankle_roll_link", "right_ankle_roll_link"), feet_are="subtree",
        foot_sites=("left_foot", "right_foot"), imu="imu_in_pelvis", base_height=0.76, self_collisions=True,
        posture={"standing": 0.05, "walking": dict(WALKING), "running": dict(RUNNING)},
        task={"rewards": {"body_ang_vel": -0.05, "angular_momentum": -0.02, "self_collisions": -1.0}},
        joint_pos={".*_hip_pitch_joint": -0.312, ".*_knee_joint": 0.669, ".*_ankle_pitch_joint": -0.363,
                   ".*_elbow_joint": 0.6, "left_shoulder_roll_joint": 0.2, "left_shoulder_pitch_joint": 0.2,
                   "right_shoulder_roll_joint": -0.2, "right_shoulder_pitch_joint": 0.2},
        actuators=(motor((".*_elbow_joint", ".*_shoulder_pitch_joint", ".*_shoulder_roll_joint",
                          ".*_shoulder_yaw_joint", ".*_wrist_roll_joint"), "5020"),
                   motor((".*_hip_pitch_joint", ".*_hip_yaw_joint", "waist_yaw_joint"), "7520_14"),
                   motor((".*_hip_roll_joint", ".*_knee_joint"), "7520_22"),
                   motor((".*_wrist_pitch_joint", ".*_wrist_yaw_joint"), "4010"),
                   motor(("waist_pitch_joint", "waist_roll_joint"), "5020", pair=2),
                   motor((".*_ankle_pitch_joint", ".*_ankle_roll_joint"), "5020", pair=2)),
        collision=Collision((".*_collision",), contype=1, conaffinity=1, condim={G1_FOOT: 3, ".*_collision": 1},
                            priority={G1_FOOT: 1, ".*": 0}, friction={G1_FOOT: (0.6,)}))


G1 = g1_robot_file()


@dataclass(frozen=True)
class G1VelocityFlat(LeggedTask):
    name: str = "G1VelocityFlat-v0"
    mirrors: str = "Mjlab-Velocity-Flat-Unitree-G1"
    scene_file: str = ""
    robot: object = G1
    root_body: str = "robot/pelvis"
    upright_body: str = "robot/torso_link"
    angvel_body: str = "robot/torso_link"
    com_body: str = "robot/torso_link"
    foot_geoms: tuple = tuple(f"robot/{s}_foot{i}_collision" for s in SIDES for i in range(1, 8))
    foot_sites: tuple = tuple(f"robot/{s}_foot" for s in SIDES)
    foot_sensors: tuple = tuple(f"feet_ground_contact_{s}_ankle_roll_link" for s in SIDES)
    self_collision_sensor: str = "self_collision_pelvis"
    nconmax: int = 48
    rewards: object = REWARDS.changed({
        "body_ang_vel": -0.05, "angular_momentum": -0.02, "self_collisions": -1.0,
        "pose": {"params": {"std_standing": PerJoint(((".*", 0.05),)), "std_walking": PerJoint(WALKING),
                            "std_running": PerJoint(RUNNING)}}}, "G1VelocityFlat-v0: rewards")


@dataclass(frozen=True)
class G1VelocityRough(G1VelocityFlat):
    """Unitree G1 on mjlab's rough ground: ``Mjlab-Velocity-Rough-Unitree-G1`` (``unitree_g1_rough_env_cfg``): the
    generated ground with its curriculum, the height scan under the pelvis in both observations, the feet's scanned
    heights and more room for contacts; the fall still ends an episode."""

    name: str = "G1VelocityRough-v0"
    mirrors: str = "Mjlab-Velocity-Rough-Unitree-G1"
    physics: tuple = (("ccd_iterations", 500),)
    nconmax: int = 70
    njmax: int = 1500
    contact_sensor_maxmatch: int = 500
    terrain: object = ROUGH_CURRICULUM
    height_scan: object = TERRAIN_SCAN
    foot_scan: object = G1_FOOT_SCAN
    policy_obs: object = with_height_scan(POLICY_OBS, TERRAIN_SCAN.max_distance, noise=0.1)
    critic_obs: object = with_height_scan(CRITIC_OBS, TERRAIN_SCAN.max_distance, noise=0.0)
    terminations: object = TERMINATIONS.changed({
        "out_of_terrain_bounds": Termination(ends.out_of_terrain_bounds, time_out=True)},
        "G1VelocityRough-v0: terminations")
