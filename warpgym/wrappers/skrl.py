"""warpgym for skrl (``pip install "warpgym[skrl]"``): its torch environment-wrapper protocol.

    from skrl.trainers.torch import SequentialTrainer
    env = SkrlVecEnv(LocomotionVecEnv("Ant", num_envs=4096, device="cuda:0"))

Zero copy, except the observations: skrl's trainer passes the previous step's observation to
``record_transition`` after the next ``step``, which overwrites warpgym's buffer in place, so the
adapter hands out a copy (one device-to-device copy per step, into two buffers used by
turns). Rewards and the terminated and
truncated flags are views of warpgym's buffers, shaped (num_envs, 1) as skrl wants them.
"""

from __future__ import annotations

import torch

try:
    from skrl.envs.wrappers.torch.base import Wrapper
except ImportError as e:  # pragma: no cover
    raise ImportError(f'the skrl adapter needs skrl: pip install "warpgym[skrl]" ({e})') from e

from warpgym.wrappers.common import EpisodeLog, ObsCopies, base_env


class SkrlVecEnv(Wrapper):
    """skrl's ``Wrapper`` over a warpgym vector env; finished envs reset inside ``step``.

    Args:
        env: a warpgym ``LocomotionVecEnv`` (or a Gymnasium wrapper of one).
        log: an ``EpisodeLog`` to feed (optional).
    """

    SHARED = {"obs": False, "reward": True, "terminated": True, "truncated": True}
    WHY_COPIED = {"obs": "skrl records the previous observation after the next step, which overwrites it"}

    def __init__(self, env, log: EpisodeLog | None = None):
        super().__init__(env)
        self._base = base_env(env)
        self._device = self._base.device
        self.log = log
        self._copies = ObsCopies(self._base.obs)
        self._reset_once = True
        self._obs = None
        self._info: dict = {}

    @property
    def observation_space(self):
        return self._base.single_observation_space

    @property
    def action_space(self):
        return self._base.single_action_space

    def reset(self):
        # skrl resets before training and, with many envs, never again: later resets happen in step
        if self._reset_once:
            obs, self._info = self._env.reset()
            self._obs = self._copies(obs)
            self._reset_once = False
        return self._obs, self._info

    def step(self, actions: torch.Tensor):
        obs, reward, terminated, truncated, info = self._env.step(actions)
        if self.log is not None:
            self.log.after_step(info)
        self._obs, self._info = self._copies(obs), info
        return self._obs, reward.view(-1, 1), terminated.view(-1, 1), truncated.view(-1, 1), info

    def state(self):
        return None

    def render(self, *args, **kwargs):
        return None

    def close(self):
        self._env.close()
