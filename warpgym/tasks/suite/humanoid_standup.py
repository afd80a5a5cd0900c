"""HumanoidStandup-v5 (gymnasium/envs/mujoco/humanoidstandup_v5.py): stand up from lying on the
floor; never terminates. The reward is the torso's height over MuJoCo's timestep (not the env's dt),
less control and impact costs, plus 1. Gymnasium v5 takes ``uph_cost_weight`` but its reward never
uses it; here too it is accepted and has no effect."""

from dataclasses import dataclass
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.suite.base import INF, GymTask
from warpgym.tasks.suite.humanoid import com_observation_size, fill_com_observation


@dataclass(frozen=True)
class HumanoidStandup(GymTask):
    name: str = "HumanoidStandup-v5"
    xml_file: str = "humanoidstandup.xml"
    frame_skip: int = 5
    nconmax: int = 64
    njmax: int = 256
    uph_cost_weight: float = 1.0
    ctrl_cost_weight: float = 0.1
    impact_cost_weight: float = 5e-7
    impact_cost_range: tuple = (-INF, 10.0)
    reset_noise_scale: float = 1e-2
    exclude_current_positions_from_observation: bool = True
    include_cinert_in_observation: bool = True
    include_cvel_in_observation: bool = True
    include_qfrc_actuator_in_observation: bool = True
    include_cfrc_ext_in_observation: bool = True

    kind: ClassVar = G.STANDUP
    info_keys: ClassVar = ("reward_linup", "reward_quadctrl", "reward_impact", "x_position", "y_position")
    contact_forces: ClassVar = True
    reset_kinematics: ClassVar = True
    reset_com: ClassVar = True
    # no forward speed, but a policy that stands up steps away from where it lay: its clips follow the torso
    camera_follows: ClassVar = True

    def observation_size(self, sim) -> int:
        return com_observation_size(self, sim)

    def fill_params(self, p, sim) -> None:
        fill_com_observation(self, p)
        p.ctrl_cost_weight = self.ctrl_cost_weight
        p.contact_cost_mode, p.contact_cost_weight = G.CONTACT_CLIPPED_COST, self.impact_cost_weight
        p.contact_lo, p.contact_hi = (float(v) for v in self.impact_cost_range)
        p.qpos_noise = p.qvel_noise = self.reset_noise_scale
