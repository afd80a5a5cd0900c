"""InvertedPendulum-v5 (gymnasium/envs/mujoco/inverted_pendulum_v5.py): keep a pole upright on a
cart; reward 1 per step, the episode ends when the pole leans more than 0.2 rad."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import GymTask


@dataclass(frozen=True)
class InvertedPendulum(GymTask):
    name: str = "InvertedPendulum-v5"
    xml_file: str = "inverted_pendulum.xml"
    frame_skip: int = 2
    reset_noise_scale: float = 0.01

    kind: ClassVar = G.PENDULUM
    info_keys: ClassVar = ("reward_survive",)
    v4_observation: ClassVar = 4

    def observation_size(self, sim) -> int:
        return sim.nq + sim.nv

    def fill_params(self, p, sim) -> None:
        p.qpos_noise = p.qvel_noise = self.reset_noise_scale
