"""Walker2d-v5 (gymnasium/envs/mujoco/walker2d_v5.py, walker2d_v5.xml): walk forward; ends when the
torso leaves its height or angle range."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import GymTask, fill_health, forward_observation_size


@dataclass(frozen=True)
class Walker2d(GymTask):
    name: str = "Walker2d-v5"
    xml_file: str = "walker2d_v5.xml"
    frame_skip: int = 4
    forward_reward_weight: float = 1.0
    ctrl_cost_weight: float = 1e-3
    healthy_reward: float = 1.0
    terminate_when_unhealthy: bool = True
    healthy_z_range: tuple = (0.8, 2.0)
    healthy_angle_range: tuple = (-1.0, 1.0)
    reset_noise_scale: float = 5e-3
    exclude_current_positions_from_observation: bool = True

    info_keys: ClassVar = ("reward_forward", "reward_ctrl", "reward_survive", "x_velocity", "x_position")
    v4_observation: ClassVar = 17
    has_speed: ClassVar = True

    def observation_size(self, sim) -> int:
        return forward_observation_size(sim, int(self.exclude_current_positions_from_observation))

    def fill_params(self, p, sim) -> None:
        p.qpos_skip = int(self.exclude_current_positions_from_observation)
        p.qvel_clip = 10.0
        p.position_source = G.POSITION_QPOS_X
        p.forward_reward_weight, p.ctrl_cost_weight = self.forward_reward_weight, self.ctrl_cost_weight
        fill_health(p, self.healthy_reward, self.terminate_when_unhealthy, 1, self.healthy_z_range,
                    angle_range=self.healthy_angle_range)
        p.qpos_noise = p.qvel_noise = self.reset_noise_scale
