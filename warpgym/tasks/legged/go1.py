"""Unitree Go1 on flat ground, following a velocity command: mjlab's ``Mjlab-Velocity-Flat-Unitree-Go1``
(``unitree_go1_flat_env_cfg``, mjlab 1.6.0).

The Go1 of MuJoCo Menagerie as mjlab's asset zoo configures it (every collision geom on, the feet with condim 6
and their own friction, position actuators of 10 Hz and damping ratio 2, elliptic friction cones), its foot
friction randomised per axis, the trunk's centre of mass offset.
"""

from dataclasses import dataclass

from warpgym.tasks.legged.base import LeggedTask, _weights

FEET = ("FR", "FL", "RR", "RL")
HIP_THIGH = r".*(FR|FL|RR|RL)_(hip|thigh)_joint.*"
CALF = r".*(FR|FL|RR|RL)_calf_joint.*"


@dataclass(frozen=True)
class Go1VelocityFlat(LeggedTask):
    name: str = "Go1VelocityFlat-v0"
    mirrors: str = "Mjlab-Velocity-Flat-Unitree-Go1"
    scene_file: str = "go1_velocity_flat.xml"
    root_body: str = "robot/trunk"
    upright_body: str = "robot/trunk"
    angvel_body: str = "robot/trunk"
    com_body: str = "robot/trunk"
    foot_geoms: tuple = tuple(f"robot/{f}_foot_collision" for f in FEET)
    foot_sites: tuple = tuple(f"robot/{f}" for f in FEET)
    foot_sensors: tuple = tuple(f"feet_ground_contact_{f}_foot_collision" for f in FEET)
    posture_std_standing: tuple = ((HIP_THIGH, 0.05), (CALF, 0.1))
    posture_std_walking: tuple = ((HIP_THIGH, 0.3), (CALF, 0.6))
    posture_std_running: tuple = ((HIP_THIGH, 0.3), (CALF, 0.6))
    nconmax: int = 32
    reward_weights: tuple = _weights()
    # condim-6 feet: sliding, torsional and rolling friction each drawn
    foot_friction: tuple = ((0, 0.3, 1.5, "uniform"), (1, 1e-4, 2e-2, "log_uniform"), (2, 1e-5, 5e-3, "log_uniform"))
