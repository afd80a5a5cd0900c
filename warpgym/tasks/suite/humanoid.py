"""Humanoid-v5 (gymnasium/envs/mujoco/humanoid_v5.py): Gymnasium's humanoid, not warpgym's
Isaac-style one (``warpgym/Humanoid-v0``). Walk forward (the mass centre's speed); ends when the
torso leaves its height range. Observes com inertias, com velocities, actuator and contact forces."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import INF, GymTask, fill_health, forward_observation_size


@dataclass(frozen=True)
class HumanoidV5(GymTask):
    name: str = "Humanoid-v5"
    xml_file: str = "humanoid.xml"
    frame_skip: int = 5
    nconmax: int = 64
    njmax: int = 256
    forward_reward_weight: float = 1.25
    ctrl_cost_weight: float = 0.1
    contact_cost_weight: float = 5e-7
    contact_cost_range: tuple = (-INF, 10.0)
    healthy_reward: float = 5.0
    terminate_when_unhealthy: bool = True
    healthy_z_range: tuple = (1.0, 2.0)
    reset_noise_scale: float = 1e-2
    exclude_current_positions_from_observation: bool = True
    include_cinert_in_observation: bool = True
    include_cvel_in_observation: bool = True
    include_qfrc_actuator_in_observation: bool = True
    include_cfrc_ext_in_observation: bool = True

    info_keys: ClassVar = ("reward_survive", "reward_forward", "reward_ctrl", "reward_contact", "x_velocity",
                           "y_velocity", "x_position")
    contact_forces: ClassVar = True
    reset_kinematics: ClassVar = True
    reset_com: ClassVar = True
    has_speed: ClassVar = True

    def observation_size(self, sim) -> int:
        return com_observation_size(self, sim)

    def fill_params(self, p, sim) -> None:
        fill_com_observation(self, p)
        p.position_source = G.POSITION_MASS_CENTER
        p.forward_reward_weight, p.ctrl_cost_weight = self.forward_reward_weight, self.ctrl_cost_weight
        p.contact_cost_mode, p.contact_cost_weight = G.CONTACT_CLIPPED_COST, self.contact_cost_weight
        p.contact_lo, p.contact_hi = (float(v) for v in self.contact_cost_range)
        fill_health(p, self.healthy_reward, self.terminate_when_unhealthy, 2, self.healthy_z_range)
        p.qpos_noise = p.qvel_noise = self.reset_noise_scale


def com_observation_size(task, sim) -> int:
    return forward_observation_size(sim, 2 * int(task.exclude_current_positions_from_observation),
                                    task.include_cinert_in_observation, task.include_cvel_in_observation,
                                    task.include_qfrc_actuator_in_observation, task.include_cfrc_ext_in_observation)


def fill_com_observation(task, p) -> None:
    """The observation both humanoids share: qpos, qvel, then what each include_* flag adds."""
    p.qpos_skip = 2 * int(task.exclude_current_positions_from_observation)
    p.obs_cinert = int(task.include_cinert_in_observation)
    p.obs_cvel = int(task.include_cvel_in_observation)
    p.obs_qfrc_actuator = int(task.include_qfrc_actuator_in_observation)
    p.obs_cfrc_ext = int(task.include_cfrc_ext_in_observation)
