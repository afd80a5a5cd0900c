"""What warpgym's vector envs share: a step that is one captured graph of Warp launches
(``_launch_step``), a reset of every world (``_launch_reset(force_all=1)``), device-side reset
noise, and the Gymnasium calls around them. ``LocomotionVecEnv`` and ``SuiteVecEnv`` fill in the
launches and buffers."""

from __future__ import annotations

import numpy as np
import torch
import warp as wp
from gymnasium.vector import VectorEnv

from kernels.locomotion import advance_rng
from warpgym.sim.checks import check_float_tensor


class GraphVecEnv(VectorEnv):
    # Set by the subclass: sim (with launch/capture), num_envs, num_actions, device, obs, reward,
    # terminated, truncated, info, _actions_in_t, _rng_state, _graph, _fault_views.

    @staticmethod
    def configured(task, max_episode_steps: int | None, overrides: dict):
        """``task`` with the constructor's keyword overrides (the task's own field names) and
        ``max_episode_steps`` as its episode length, checked."""
        if max_episode_steps is not None:
            overrides["episode_length"] = max_episode_steps
        if overrides:
            task = task.replace(**overrides)
        task.validate()
        return task

    def _launch_step(self) -> None:
        raise NotImplementedError

    def _launch_reset(self, force_all: int) -> None:
        raise NotImplementedError

    def _reset_all(self) -> None:
        def run():
            self._launch_reset(force_all=1)
            wp.launch(advance_rng, dim=1, inputs=[self._rng_state], device=self.sim.device)

        self.sim.launch(None, run)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        """Reset every env. With ``seed``, the noise of this and all later resets is reproducible."""
        if seed is not None:
            self._rng_state.assign(np.array([int(seed) & 0x7FFFFFFF, 0], np.int32))
        self._reset_all()
        return self.obs, {}

    def step(self, actions: torch.Tensor | np.ndarray):
        """Step every env. ``actions`` (num_envs, num_actions): a float32 tensor on the env's device
        (the zero-copy path), or a numpy array as Gymnasium learners pass, copied to the device here
        (one host-to-device copy per step)."""
        if isinstance(actions, np.ndarray):
            actions = torch.as_tensor(actions, dtype=torch.float32, device=self.device)
        actions = check_float_tensor("actions", actions, self.device, [(self.num_envs, self.num_actions)])
        self._actions_in_t.copy_(actions)
        if self._graph is None:
            self._graph = self.sim.capture(self._launch_step)
        self.sim.launch(self._graph, self._launch_step)
        return self.obs, self.reward, self.terminated, self.truncated, self.info

    def fault_counters(self) -> dict[str, torch.Tensor]:
        """Running totals since the env was built of things that should never happen (agents.protocol):
        non-finite action entries, diverged worlds, and world-steps that lost constraints. Device
        tensors; reading them costs nothing until they are copied to the host."""
        return self._fault_views
