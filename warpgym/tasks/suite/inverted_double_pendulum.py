"""InvertedDoublePendulum-v5 (gymnasium/envs/mujoco/inverted_double_pendulum_v5.py): balance two
poles on a cart; the episode ends when the tip drops to 1 m."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import GymTask


@dataclass(frozen=True)
class InvertedDoublePendulum(GymTask):
    name: str = "InvertedDoublePendulum-v5"
    xml_file: str = "inverted_double_pendulum.xml"
    frame_skip: int = 5
    healthy_reward: float = 10.0
    reset_noise_scale: float = 0.1

    kind: ClassVar = G.DOUBLE_PENDULUM
    info_keys: ClassVar = ("reward_survive", "distance_penalty", "velocity_penalty")
    v4_observation: ClassVar = 9  # v4 adds two hinge constraint forces, always 0

    def observation_size(self, sim) -> int:
        return 2 * sim.nq - 1 + sim.nv + 1

    def fill_params(self, p, sim) -> None:
        p.healthy_reward = self.healthy_reward
        p.qpos_noise = p.qvel_noise = self.reset_noise_scale
        p.qvel_noise_normal = 1
