"""HalfCheetah-v5 (gymnasium/envs/mujoco/half_cheetah_v5.py): run forward; never terminates."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import GymTask, forward_observation_size


@dataclass(frozen=True)
class HalfCheetah(GymTask):
    name: str = "HalfCheetah-v5"
    xml_file: str = "half_cheetah.xml"
    frame_skip: int = 5
    forward_reward_weight: float = 1.0
    ctrl_cost_weight: float = 0.1
    reset_noise_scale: float = 0.1
    exclude_current_positions_from_observation: bool = True

    info_keys: ClassVar = ("reward_forward", "reward_ctrl", "x_velocity", "x_position")
    v4_observation: ClassVar = 17
    has_speed: ClassVar = True

    def observation_size(self, sim) -> int:
        return forward_observation_size(sim, int(self.exclude_current_positions_from_observation))

    def fill_params(self, p, sim) -> None:
        p.qpos_skip = int(self.exclude_current_positions_from_observation)
        p.position_source = G.POSITION_QPOS_X
        p.forward_reward_weight, p.ctrl_cost_weight = self.forward_reward_weight, self.ctrl_cost_weight
        p.qpos_noise = p.qvel_noise = self.reset_noise_scale
        p.qvel_noise_normal = 1
