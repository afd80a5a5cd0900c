"""What warpgym's vector envs share: a step that is one captured graph of Warp launches
(``_launch_step``), a reset of every world (``_launch_reset(force_all=1)``), device-side reset
noise, and the Gymnasium calls around them. ``LocomotionVecEnv`` and ``SuiteVecEnv`` fill in the
launches and buffers."""

from __future__ import annotations

import numpy as np
import torch
import warp as wp
from gymnasium import logger as gymnasium_logger
from gymnasium.vector import VectorEnv

from kernels.common import StepOutputs, advance_rng, count_faults
from warpgym.sim.checks import check_float_tensor


class GraphVecEnv(VectorEnv):
    """The common part of warpgym's vector envs. An env class derived from it names ``VectorEnv`` among its own
    direct bases too: skrl's ``wrap_env`` (auto) looks for a Gymnasium class among an env class's direct bases
    only, and finding ``GraphVecEnv`` there refused the env (tests/test_learner_entry_points.py)."""

    # Set by the subclass before _alloc_common and _expose: sim (with launch/capture), num_envs,
    # num_actions, device; _view (a renderer or None) before render.
    FAULTS = ("nan_actions", "diverged_resets", "solver_overflows")  # fault_counters' names, in _fault_totals' order
    # what each fault means and its fix, for agents.protocol's messages; the subclasses add the other two
    FAULT_HELP = {"nan_actions": "the policy sent NaN/inf actions; they were applied as 0"}
    # until the subclass sets it: a constructor that raised (a wrong kwarg) leaves an object that Gymnasium's
    # VectorEnv.__del__ still closes
    _view = None

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

    @classmethod
    def replay_args(cls, env_args: dict) -> dict:
        """The constructor's keywords that rebuild the env a run trained on, from the ``env_args`` it saved."""
        return dict(env_args)

    def _buf(self, shape, dtype=float) -> wp.array:
        """A zeroed Warp array on the env's device."""
        return wp.zeros(shape, dtype=dtype, device=self.sim.device)

    def _alloc_common(self, n: int, num_obs: int, num_actions: int, seed: int) -> StepOutputs:
        """The buffers every env's step uses alike: the actions coming in, the step's outputs, the fault
        counts (non-finite actions per world; totals of non-finite actions, diverged worlds and
        overflowed substeps) and the reset noise's random state. Returns the outputs (``self._out``)."""
        dev, buf = self.sim.device, self._buf

        self._actions_in = buf((n, num_actions))
        self._nan_count = buf(n, wp.int32)
        self._fault_totals = buf(3, wp.int64)
        self._rng_state = wp.array(np.array([seed, 0], np.int32), dtype=wp.int32, device=dev)
        self._out = out = StepOutputs()
        out.obs, out.final_obs, out.reward = buf((n, num_obs)), buf((n, num_obs)), buf(n)
        out.terminated, out.truncated, out.time_outs = buf(n, wp.bool), buf(n, wp.bool), buf(n, wp.bool)
        out.done, out.diverged = buf(n, wp.bool), buf(n, wp.bool)
        return out

    def _expose(self, info: dict) -> None:
        """Make the torch views every step hands out (the task's ``info`` entries, then the final
        observations and the fault entries every env reports), compile every kernel a step launches side
        by side rather than one by one inside the first step (warpgym.compile.preload; a warm cache
        makes this a quick check), capture the step and reset every world."""
        t, out = self.sim.to_torch, self._out
        self._actions_in_t = t(self._actions_in)
        self.obs, self.reward = t(out.obs), t(out.reward)
        self.terminated, self.truncated = t(out.terminated), t(out.truncated)
        # "time_outs": truncated and not terminated, what Isaac-style learners bootstrap (rsl_rl, rl_games)
        self.info = {**info, "final_obs": t(out.final_obs), "_final_obs": t(out.done), "time_outs": t(out.time_outs),
                     "nan_actions": t(self._nan_count), "diverged": t(out.diverged),
                     "solver_overflows": t(self.sim.solver_overflows)}
        totals = t(self._fault_totals)
        self._fault_views = {name: totals[i] for i, name in enumerate(self.FAULTS)}
        # captured before the first reset: a capture's host-side effects (the memsets and copies inside MuJoCo
        # Warp's step, which run while its launches are only recorded) then fall on worlds the reset writes whole,
        # never on a state that a step, write_state or a forward pass left for the next step to start from
        self._graph = self.sim.capture(self._launch_step)
        self._reset_all()

    def _launch_step(self) -> None:
        raise NotImplementedError

    def _finish_step(self) -> None:
        """The end of every env's step, after its task kernel: reset the worlds that finished, add this
        step's faults to the totals, and move the reset noise's random state on."""
        sim, n = self.sim, self.num_envs
        self._launch_reset(force_all=0)
        wp.launch(count_faults, dim=n, inputs=[self._nan_count, self._out.diverged, sim.solver_overflows],
                  outputs=[self._fault_totals], device=sim.device)
        wp.launch(advance_rng, dim=1, inputs=[self._rng_state], device=sim.device)

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

    def call(self, name: str, *args, **kwargs):
        """Gymnasium's ``SyncVectorEnv.call``, which learners use to reach the sub-environments (skrl's wrapper
        renders through ``call("render")``). warpgym's worlds are not separate envs, so the call goes to this env:
        a method's result (``render``: its tuple of frames, one per drawn world), or an attribute's value."""
        value = getattr(self, name)
        return value(*args, **kwargs) if callable(value) else value

    def render(self):
        """Gymnasium's render: a tuple of (height, width, 3) uint8 frames of the first ``render_robots`` worlds
        ("rgb_array"), or the viewer updated ("human"). One host copy of their states."""
        if self._view is None:
            gymnasium_logger.warn("render() was called on an env made without render_mode: pass render_mode="
                                  "'rgb_array' (or 'human') to gym.make / gym.make_vec")
            return None
        return self._draw(min(self._view.robots, self.num_envs))

    def _draw(self, k: int):
        """The renderer's frames of the first ``k`` worlds."""
        raise NotImplementedError

    def close(self, **kwargs) -> None:
        self._graph = None
        if self._view is not None:
            self._view.close()
        self.closed = True

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.task.name}, num_envs={self.num_envs}, device={self.sim.device!r})"

    def fault_counters(self) -> dict[str, torch.Tensor]:
        """Running totals since the env was built of things that should never happen (agents.protocol):
        non-finite action entries, diverged worlds, and world-steps that lost constraints. Device
        tensors; reading them costs nothing until they are copied to the host."""
        return self._fault_views
