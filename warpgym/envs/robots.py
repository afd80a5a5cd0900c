"""Ant and Humanoid as a Gymnasium vector environment whose every step is Warp kernels.

A step is: copy the actions into a persistent buffer, then one graph launch (apply actions,
physics substeps, contact and joint forces, observations, rewards, dones, masked resets). The
returned tensors are persistent buffers that the next step overwrites: clone what you keep.
"""

from __future__ import annotations

import numpy as np
import warp as wp
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from kernels.robots.actions import apply_actions
from kernels.robots.buffers import EpisodeBuffers, RobotState, RobotView
from kernels.robots.step import step_kernel
from kernels.robots.resets import reset_finished_envs
from warpgym.envs.graph_env import GraphVecEnv
from warpgym.envs.single import SingleEnv
from warpgym.sim.simulator import Sim
from warpgym.tasks.robots import LocomotionTask, get_task
from warpgym.tasks.terms import compile_own_tables


# VectorEnv is named again beside GraphVecEnv (which is one): skrl's wrap_env(env) and other learners tell a
# Gymnasium env by its class's direct bases (see GraphVecEnv)
class LocomotionVecEnv(GraphVecEnv, VectorEnv):
    """``num_envs`` copies of a locomotion task on one device; tensors in, tensors out.

    Args:
        task: "Ant", "Humanoid" or a ``LocomotionTask``.
        num_envs: number of parallel environments.
        device: "cpu" or "cuda:N" (default: cuda:0 when present).
        seed: seed of the reset noise; ``reset(seed=...)`` replaces it.
        max_episode_steps: episode length (default: the task's, 1000).
        sim_options: extra ``Sim`` arguments (njmax, nconmax, check_inputs).
        render_mode: None, "rgb_array" (``render()`` returns a tuple with one frame per robot for the
            first ``render_robots``) or "human" (MuJoCo's viewer on the first robot; needs a display).
        render_robots: how many robots an "rgb_array" render draws, each with its own camera.
        render_size: (width, height) of those frames in pixels.
        **task_overrides: any ``LocomotionTask`` field, e.g. ``termination_height=0.25``, ``substeps=4`` or
            ``physics={"armature": 0.05}`` (merged into the task's ``Physics``).
    """

    # one frame per 1/60 s control step (render_fps follows a task's dt when it differs)
    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": ["rgb_array", "human"], "render_fps": 60}
    # step() never waits on the host and returns persistent buffers, so a learner may record it into
    # a torch CUDA graph (agents.protocol); the Warp launches then join torch's capture.
    graph_capturable = True

    @classmethod
    def replay_args(cls, env_args: dict) -> dict:
        """A saved run's env: its physics as recorded, a setting added since then off (``recorded``), not
        today's defaults, which would replay an old policy on physics it never saw."""
        from warpgym.sim.physics import recorded  # noqa: PLC0415

        return {**env_args, "physics": recorded(env_args.get("physics"))}

    def __init__(
        self,
        task: str | LocomotionTask = "Ant",
        num_envs: int = 1,
        device: str | None = None,
        seed: int = 0,
        max_episode_steps: int | None = None,
        sim_options: dict | None = None,
        render_mode: str | None = None,
        render_robots: int = 1,
        render_size: tuple[int, int] = (640, 480),
        **task_overrides,
    ):
        self.task = task = self.configured(get_task(task), max_episode_steps, task_overrides)
        self.render_mode = render_mode
        self._view = None
        if render_mode is not None:
            from warpgym.media.robots import EnvView  # noqa: PLC0415  (MuJoCo's renderer: only when asked for)

            self._view = EnvView(task, render_mode, render_robots, *render_size)
            if round(1.0 / task.dt) != self.metadata["render_fps"]:
                self.metadata = {**self.metadata, "render_fps": round(1.0 / task.dt)}
        self.sim = sim = Sim(task.robot, num_envs, device, seed, dt=task.dt, substeps=task.substeps,
                             physics=task.physics, **(sim_options or {}))
        self.num_envs = n = sim.num_envs
        self.device = sim.torch_device
        self.num_actions = a = sim.num_dofs
        self.num_obs = o = task.observation_size(a, sim.foot_bodies.shape[0])

        self.single_observation_space = spaces.Box(-np.inf, np.inf, (o,), np.float32)
        self.single_action_space = spaces.Box(-1.0, 1.0, (a,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)

        dev = sim.device
        gear = sim.motor_gear_np
        self.params = task.to_warp(sim.spec.start_height)
        self._torque_scale = wp.array(gear * task.power_scale, dtype=float, device=dev)
        out = self._alloc_common(n, o, a, seed)
        buf = self._buf

        if task.contact_force_scale != 0.0:
            sim.enable_contact_forces()

        self._robot = robot = RobotView()
        robot.joint_q, robot.joint_qd = sim.joint_q, sim.joint_qd
        robot.dof_lower = wp.array(sim.dof_lower_np, dtype=float, device=dev)
        robot.dof_upper = wp.array(sim.dof_upper_np, dtype=float, device=dev)
        robot.default_dof_pos = wp.array(sim.default_dof_pos_np, dtype=float, device=dev)
        robot.effort_ratio = wp.array(gear / gear.max(), dtype=float, device=dev)
        robot.dof_force, robot.contact_wrench = sim.dof_force_buffer(), sim.contact_wrench_buffer()
        robot.foot_bodies, robot.bodies_per_env = sim.foot_bodies, sim.bodies_per_env
        robot.actions = buf((n, a))
        robot.warm_start = sim.solver.mjw_data.qacc_warmstart

        self._episodes = ep = EpisodeBuffers()
        ep.potential, ep.length, ep.total_return, ep.speed = buf(n), buf(n, wp.int32), buf(n), buf(n)
        ep.ended_return, ep.ended_length, ep.ended_speed = buf(n), buf(n, wp.int32), buf(n)
        ep.extra = buf((n, max(1, len(task.rewards))))
        self._own_terms(task, sim.dof_names, dev)

        t = sim.to_torch
        self.actions = t(robot.actions)
        # steps into each env's episode (int32); writable, e.g. to spread the first episodes' ends
        self.episode_steps = t(ep.length)
        done = t(out.done)
        self._expose({
            "episode": {"r": t(ep.ended_return), "l": t(ep.ended_length), "s": t(ep.ended_speed),
                        "_r": done, "_l": done, "_s": done},
            "_episode": done,
            # the episode in progress after this step (a fresh one where the step reset the env):
            # what an evaluation cut short reports (agents.evaluate)
            "episode_so_far": {"r": t(ep.total_return), "l": t(ep.length), "s": t(ep.speed)},
            **{key: t(ep.extra)[:, k] for k, key in enumerate(task.own_terms())},
        })

    def _own_terms(self, task: LocomotionTask, joints: list[str], dev: str) -> None:
        """The task's own reward and termination terms compiled into its step kernel (tasks without any share one
        kernel), over the state they read (``RobotState``)."""
        self._rewards, self._terminations = compile_own_tables(task, RobotState, joints, dev)
        self._step_kernel = step_kernel(self._rewards.func, self._rewards.params_type, self._terminations.func,
                                        self._terminations.params_type)
        self._state = state = RobotState()
        state.p, state.r, state.ep, state.obs = self.params, self._robot, self._episodes, self._out.obs

    # ------------------------------------------------------------------ device work
    def _launch_step(self) -> None:
        sim, n, dev = self.sim, self.num_envs, self.sim.device
        wp.launch(apply_actions, dim=n, inputs=[self._actions_in, self._torque_scale],
                  outputs=[self._robot.actions, sim.joint_f, self._nan_count], device=dev)
        sim.simulate()
        if self.task.contact_force_scale != 0.0:
            sim.compute_contact_wrenches()
        if self.task.observe_dof_forces:
            sim.compute_dof_forces()
        r, t = self._rewards, self._terminations
        wp.launch(self._step_kernel, dim=n, inputs=[self._state, r.params, r.arrays, t.params, self._out], device=dev)
        self._finish_step()

    def _launch_reset(self, force_all: int) -> None:
        wp.launch(reset_finished_envs, dim=self.num_envs,
                  inputs=[self.params, force_all, self._rng_state, self._robot, self._episodes, self._out],
                  device=self.sim.device)

    # ------------------------------------------------------------------ rendering and fault texts (GraphVecEnv: the Gymnasium API)
    FAULT_HELP = {
        **GraphVecEnv.FAULT_HELP,
        "diverged_resets": "a world's physics blew up (NaN or beyond max_speed); it was reset with reward 0",
        "solver_overflows": "MuJoCo Warp's constraint or contact buffers were full and a world lost constraints "
                            "for a substep; raise njmax/nconmax (sim_options) above the peak in Sim.solver_load()",
    }

    def _draw(self, k: int):
        states = {key: getattr(self.sim, key)[:k].cpu().numpy() for key in ("root_pose", "root_vel", "dof_pos", "dof_vel")}
        return self._view.render(states)


class LocomotionEnv(SingleEnv):
    """One world of warpgym's Ant or Humanoid (``gym.make("warpgym/Ant-v0")``): numpy in and out, the reward terms
    in ``info``."""

    vec_class = LocomotionVecEnv
    metadata = LocomotionVecEnv.metadata

    def __init__(self, task="Ant", device: str = "cpu", seed: int = 0, render_mode=None, **kwargs):
        super().__init__(task, device, seed, render_mode, **kwargs)
