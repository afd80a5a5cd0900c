"""Ant-v5 (gymnasium/envs/mujoco/ant_v5.py): Gymnasium's quadruped, not warpgym's Isaac-style Ant
(``warpgym/Ant-v0``). Walk forward; ends when the torso leaves its height range or the state is
not finite. Observes clipped external contact forces."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import GymTask, fill_health, forward_observation_size


@dataclass(frozen=True)
class AntV5(GymTask):
    name: str = "Ant-v5"
    xml_file: str = "ant.xml"
    frame_skip: int = 5
    forward_reward_weight: float = 1.0
    ctrl_cost_weight: float = 0.5
    contact_cost_weight: float = 5e-4
    healthy_reward: float = 1.0
    main_body: int | str = 1
    terminate_when_unhealthy: bool = True
    healthy_z_range: tuple = (0.2, 1.0)
    contact_force_range: tuple = (-1.0, 1.0)
    reset_noise_scale: float = 0.1
    exclude_current_positions_from_observation: bool = True
    include_cfrc_ext_in_observation: bool = True

    info_keys: ClassVar = ("reward_forward", "reward_ctrl", "reward_contact", "reward_survive", "x_velocity",
                           "y_velocity", "x_position")
    contact_forces: ClassVar = True
    reset_kinematics: ClassVar = True
    has_speed: ClassVar = True

    def observation_size(self, sim) -> int:
        return forward_observation_size(sim, 2 * int(self.exclude_current_positions_from_observation),
                                        cfrc_ext=self.include_cfrc_ext_in_observation)

    def fill_params(self, p, sim) -> None:
        p.qpos_skip = 2 * int(self.exclude_current_positions_from_observation)
        p.obs_cfrc_ext = int(self.include_cfrc_ext_in_observation)
        p.cfrc_lo, p.cfrc_hi = (float(v) for v in self.contact_force_range)
        p.position_source, p.main_body = G.POSITION_BODY, self.body(sim, self.main_body)
        p.forward_reward_weight, p.ctrl_cost_weight = self.forward_reward_weight, self.ctrl_cost_weight
        p.contact_cost_mode, p.contact_cost_weight = G.CONTACT_CLIPPED_FORCES, self.contact_cost_weight
        fill_health(p, self.healthy_reward, self.terminate_when_unhealthy, 2, self.healthy_z_range, inclusive=True,
                    finite=True)
        p.qpos_noise = p.qvel_noise = self.reset_noise_scale
        p.qvel_noise_normal = 1
