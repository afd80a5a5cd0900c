"""Gymnasium's MuJoCo tasks (v5) as a vector environment whose every step stays on the device.

A step: the actions into MuJoCo Warp's controls, ``frame_skip`` physics steps, Gymnasium's
observation, reward and termination, then the finished worlds reset and their first observation
written, all one graph launch. Tensors are float32 on the env's device (Gymnasium's own envs return
float64 numpy arrays) and persistent: the next step overwrites them.
"""

from __future__ import annotations

import numpy as np
import warp as wp
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from kernels.suite.params import GymEpisodes, MjView, SuiteState
from kernels.suite.resets import reset_gym_worlds
from kernels.suite.step import apply_gym_actions, step_kernel, write_reset_observation
from warpgym.envs.graph_env import GraphVecEnv
from warpgym.envs.single import SingleEnv
from warpgym.sim.mjw_sim import MjwSim
from warpgym.tasks.suite import GymTask, get_suite_task
from warpgym.tasks.suite.base import MAX_TERMS
from warpgym.tasks.terms import compile_own_tables


# VectorEnv is named again beside GraphVecEnv (which is one): skrl's wrap_env(env) and other learners tell a
# Gymnasium env by its class's direct bases (see GraphVecEnv)
class SuiteVecEnv(GraphVecEnv, VectorEnv):
    """``num_envs`` worlds of one of Gymnasium's MuJoCo tasks; tensors in, tensors out. Actions are not
    clipped: MuJoCo clamps the controls to their range and the control cost is charged on the actions as
    given, as in Gymnasium (``unit_actions`` below maps [-1, 1] onto the ranges instead).

    Args:
        task: a suite id ("Hopper-v5", ...) or a ``GymTask``.
        num_envs: parallel environments.
        device: "cpu" or "cuda:N" (default: cuda:0 when present).
        seed: seed of the reset noise; ``reset(seed=...)`` replaces it.
        max_episode_steps: the time limit (default: Gymnasium's for the task).
        render_mode: None, "rgb_array" (``render()`` returns a tuple with one frame per world for the first
            ``render_robots``, drawn by Gymnasium's own env of the task from these worlds' states) or "human".
        render_robots, render_size: how many worlds an "rgb_array" render draws, and (width, height).
        unit_actions: take actions in [-1, 1], clip them there and map them linearly onto the actuators'
            control ranges, as a learner that rescales its actions before Gymnasium's env (SB3's
            ``unscale_action``) does; the control cost is charged on the mapped controls. The action
            space is then [-1, 1]. Default False: Gymnasium's own action space and actions as given.
        **kwargs: Gymnasium's constructor arguments of the task (e.g. ``ctrl_cost_weight=0.5``,
            ``frame_skip=2``, ``xml_file=PATH``), ``nconmax`` / ``njmax`` for MuJoCo Warp's buffers, and the task's
            own terms beside Gymnasium's: ``rewards={"upright": Reward(func, weight=0.1)}``, ``terminations``
            (``warpgym.tasks.terms``; a term's function reads ``kernels.suite.params.SuiteState``).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": ["rgb_array", "human"]}
    graph_capturable = True
    FAULT_HELP = {
        **GraphVecEnv.FAULT_HELP,
        "diverged_resets": "a world's state stopped being finite; it ended with reward 0 and was reset",
        "solver_overflows": "MuJoCo Warp's constraint or contact buffers were full and a world lost constraints for "
                            "a physics step: pass larger nconmax / njmax",
    }

    def __init__(self, task: str | GymTask = "Hopper-v5", num_envs: int = 1, device: str | None = None, seed: int = 0,
                 max_episode_steps: int | None = None, render_mode: str | None = None, render_robots: int = 1,
                 render_size: tuple[int, int] = (480, 480), unit_actions: bool = False, **kwargs):
        self.task = task = self.configured(get_suite_task(task), max_episode_steps, kwargs)
        self.render_mode = render_mode
        self._view = None
        if render_mode is not None:
            from warpgym.media.suite import SuiteView  # noqa: PLC0415  (Gymnasium's renderer: only when asked for)

            self._view = SuiteView(task, render_mode, render_robots, *render_size)
        self.sim = sim = MjwSim(task.xml_file, num_envs, device, frame_skip=task.frame_skip, nconmax=task.nconmax,
                                njmax=task.njmax, contact_forces=task.contact_forces)
        self.num_envs = n = sim.num_envs
        self.device = sim.torch_device
        self.num_actions = a = sim.nu
        self.num_obs = o = task.observation_size(sim)
        self.metadata = {**self.metadata, "render_fps": int(np.round(1.0 / sim.dt))}

        low, high = sim.ctrl_range[:, 0], sim.ctrl_range[:, 1]
        self.unit_actions = bool(unit_actions)
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (o,), np.float32)
        self.single_action_space = (spaces.Box(-1.0, 1.0, (a,), np.float32) if self.unit_actions
                                    else spaces.Box(low, high, (a,), np.float32))
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)

        dev = sim.device
        self.params = task.params(sim)
        buf = self._buf

        d = sim.d
        self._mj = view = MjView()
        view.qpos, view.qvel, view.ctrl = d.qpos, d.qvel, d.ctrl
        view.xpos, view.xipos, view.cinert, view.cvel = d.xpos, d.xipos, d.cinert, d.cvel
        view.cfrc_ext, view.qfrc_actuator, view.qfrc_constraint = d.cfrc_ext, d.qfrc_actuator, d.qfrc_constraint
        view.site_xpos, view.warm_start = d.site_xpos, d.qacc_warmstart
        mjm = sim.mjm
        view.body_mass = wp.array(mjm.body_mass.astype(np.float32), dtype=float, device=dev)
        view.qpos0 = wp.array(mjm.qpos0.astype(np.float32), dtype=float, device=dev)
        view.total_mass = float(mjm.body_mass.sum())

        self._episodes = ep = GymEpisodes()
        ep.before, ep.length, ep.total_return = buf((n, 2)), buf(n, wp.int32), buf(n)
        ep.travel, ep.speed = buf(n), buf(n)
        ep.ended_return, ep.ended_length, ep.ended_speed = buf(n), buf(n, wp.int32), buf(n)
        ep.terms, ep.actions = buf((n, MAX_TERMS)), buf((n, a))
        ep.extra = buf((n, max(1, len(task.rewards))))
        self._own_terms(task, sim, dev)

        out = self._alloc_common(n, o, a, seed)
        self._ctrl_low = wp.array(low, dtype=float, device=dev)
        self._ctrl_high = wp.array(high, dtype=float, device=dev)

        t = sim.to_torch
        self.actions = t(ep.actions)
        self.episode_steps = t(ep.length)
        done = t(out.done)
        terms = t(ep.terms)
        episode = {"r": t(ep.ended_return), "l": t(ep.ended_length), "_r": done, "_l": done}
        so_far = {"r": t(ep.total_return), "l": t(ep.length)}
        if task.has_speed:
            episode.update(s=t(ep.ended_speed), _s=done)
            so_far["s"] = t(ep.speed)
        extra = t(ep.extra)
        self._expose({**{key: terms[:, col] for key, col in task.term_columns().items()},
                      **{key: extra[:, k] for k, key in enumerate(task.own_terms())},
                      "episode": episode, "_episode": done, "episode_so_far": so_far})

    def _own_terms(self, task: GymTask, sim, dev: str) -> None:
        """The task's own reward and termination terms compiled into its step kernel (tasks without any share
        one kernel), over the state they read (``SuiteState``)."""
        import mujoco  # noqa: PLC0415

        mjm = sim.mjm
        joints = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_JOINT, int(mjm.actuator_trnid[i, 0])) or f"joint{i}"
                  for i in range(mjm.nu)]  # a PerJoint parameter: a value per actuator's joint
        self._rewards, self._terminations = compile_own_tables(task, SuiteState, joints, dev)
        self._step_kernel = step_kernel(self._rewards.func, self._rewards.params_type, self._terminations.func,
                                        self._terminations.params_type)
        self._state = state = SuiteState()
        state.p, state.d, state.ep = self.params, self._mj, self._episodes

    # ------------------------------------------------------------------ device work
    def _launch_step(self) -> None:
        sim, n, dev = self.sim, self.num_envs, self.sim.device
        wp.launch(apply_gym_actions, dim=n,
                  inputs=[self._actions_in, int(self.unit_actions), self._ctrl_low, self._ctrl_high],
                  outputs=[sim.d.ctrl, self._episodes.actions, self._nan_count], device=dev)
        sim.simulate()
        r, t = self._rewards, self._terminations
        wp.launch(self._step_kernel, dim=n, inputs=[self._state, r.params, r.arrays, t.params, self._out], device=dev)
        self._finish_step()

    def _launch_reset(self, force_all: int) -> None:
        dev = self.sim.device
        wp.launch(reset_gym_worlds, dim=self.num_envs,
                  inputs=[self.params, force_all, self._rng_state, self._mj, self._episodes, self._out], device=dev)
        if self.task.reset_kinematics:  # all worlds: the others' observations are already written
            self.sim.kinematics(com=self.task.reset_com)
        wp.launch(write_reset_observation, dim=self.num_envs,
                  inputs=[self.params, force_all, self._mj, self._episodes, self._out], device=dev)

    # ------------------------------------------------------------------ rendering and fault texts (GraphVecEnv: the Gymnasium API)
    def _draw(self, k: int):
        return self._view.render(self.sim.dof_pos[:k].cpu().numpy(), self.sim.dof_vel[:k].cpu().numpy())


class SuiteEnv(SingleEnv):
    """One world of Gymnasium's MuJoCo task (``gym.make("warpgym/Hopper-v5")``): numpy float32 in and out,
    Gymnasium's reward terms in ``info``."""

    vec_class = SuiteVecEnv
    metadata = SuiteVecEnv.metadata

    def __init__(self, task="Hopper-v5", device: str = "cpu", seed: int = 0, render_mode=None, **kwargs):
        super().__init__(task, device, seed, render_mode, **kwargs)
