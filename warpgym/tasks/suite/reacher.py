"""Reacher-v5 (gymnasium/envs/mujoco/reacher_v5.py): move a two-link arm's fingertip to a target
drawn in a 0.2 m disc; 50 steps, never terminates."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import GymTask


@dataclass(frozen=True)
class Reacher(GymTask):
    name: str = "Reacher-v5"
    xml_file: str = "reacher.xml"
    frame_skip: int = 2
    episode_length: int = 50
    reward_dist_weight: float = 1.0
    reward_control_weight: float = 1.0

    kind: ClassVar = G.REACHER
    info_keys: ClassVar = ("reward_dist", "reward_ctrl")
    v4_observation: ClassVar = 10  # v4 adds the fingertip's height above the target, always 0
    reset_kinematics: ClassVar = True

    def observation_size(self, sim) -> int:
        return 10

    def fill_params(self, p, sim) -> None:
        p.body_a, p.body_b = self.body(sim, "fingertip"), self.body(sim, "target")
        p.dist_weight, p.ctrl_cost_weight = self.reward_dist_weight, self.reward_control_weight
        p.qpos_noise, p.qvel_noise, p.goal_mode = 0.1, 0.005, G.GOAL_REACHER
