"""Pusher-v5 (gymnasium/envs/mujoco/pusher_v5.py, pusher_v5.xml): push a cylinder to the goal with a
7-joint arm; 100 steps, never terminates."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import GymTask


@dataclass(frozen=True)
class Pusher(GymTask):
    name: str = "Pusher-v5"
    xml_file: str = "pusher_v5.xml"
    frame_skip: int = 5
    episode_length: int = 100
    reward_near_weight: float = 0.5
    reward_dist_weight: float = 1.0
    reward_control_weight: float = 0.1

    kind: ClassVar = G.PUSHER
    info_keys: ClassVar = ("reward_dist", "reward_ctrl", "reward_near")
    reset_kinematics: ClassVar = True

    def observation_size(self, sim) -> int:
        return 23

    def fill_params(self, p, sim) -> None:
        p.body_a, p.body_b, p.body_c = (self.body(sim, n) for n in ("tips_arm", "object", "goal"))
        p.near_weight, p.dist_weight = self.reward_near_weight, self.reward_dist_weight
        p.ctrl_cost_weight = self.reward_control_weight
        p.qpos_noise, p.qvel_noise, p.goal_mode = 0.0, 0.005, G.GOAL_PUSHER
