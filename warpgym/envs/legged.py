"""Legged robots following a velocity command (mjlab's velocity tasks) as a vector environment whose every step
stays on the device.

A step, as mjlab's ``ManagerBasedRlEnv.step`` orders it: the actions into position targets, ``decimation``
physics steps (each followed by the feet's contact bookkeeping), terminations, reward terms and interval events
(pushes) from the data the physics left, the finished worlds reset (with their reset events), MuJoCo's forward
pass of every world, the commands' timers and steering, and both observations; all one graph launch. ``obs`` is
the policy's observation (with noise); ``info["critic_obs"]`` is the critic's (privileged: no noise or encoder bias, the feet's heights, air times,
contacts and forces), ``info["final_critic_obs"]`` the one an episode ended on.
"""

from __future__ import annotations

import numpy as np
import torch
import warp as wp
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from kernels.legged.commands import update_commands
from kernels.legged.control import apply_legged_actions, track_feet
import kernels.legged.params as terms_state  # its LeggedEnv, the struct every term reads, beside this module's own
from kernels.legged.params import NUM_GROUPS, LeggedEpisodes, LeggedState, MjLegged, MjLeggedModel, TerrainLevels
from kernels.legged.resets import reset_kernels
from kernels.legged.scan import fit_ground_normal
from kernels.legged.step import count_step, step_kernels
from kernels.legged.terrain_levels import move_levels
from warpgym.envs.graph_env import GraphVecEnv
from warpgym.envs.single import SingleEnv
from warpgym.sim.mjw_sim import MjwSim
from warpgym.sim.rays import RayCaster, Scan, ScanFrames
from warpgym.tasks.legged import LeggedTask, get_legged_task
from warpgym.tasks.legged.levels import bounds, start_levels
from warpgym.tasks.legged.model import compile_task_scene, dims, kernel_structs, resolve
from warpgym.tasks.legged.scan import normal_picks
from warpgym.tasks.terms import (compile_events, compile_observations, compile_rewards, compile_terminations, layout,
                                 of_mode)

# the model fields events may change per world (MjLeggedModel), and those MuJoCo Warp's set_const derives from them
# (mjlab's list)
RANDOMISED_FIELDS = ("geom_friction", "body_ipos")
DERIVED_FIELDS = ("body_subtreemass", "dof_invweight0", "body_invweight0", "tendon_length0", "tendon_invweight0",
                  "actuator_acc0")


class LeggedVecEnv(GraphVecEnv, VectorEnv):
    """``num_envs`` worlds of one legged velocity task; tensors in, tensors out. Actions are joint position
    offsets scaled as mjlab scales them (no clipping: mjlab's action space is unbounded).

    Args:
        task: "Go1VelocityFlat-v0", "G1VelocityFlat-v0" or a ``LeggedTask``.
        num_envs: parallel environments.
        device: "cpu" or "cuda:N" (default: cuda:0 when present).
        seed: seed of every random draw (events, commands, noise); ``reset(seed=...)`` replaces it for what
            follows.
        max_episode_steps: the time limit in control steps (default: the task's 20 s, 1000 steps).
        **kwargs: the task's fields (``LeggedTask``: command ranges, changes of its tables of terms, ...).
    """

    metadata = {"autoreset_mode": AutoresetMode.SAME_STEP, "render_modes": []}
    graph_capturable = True
    FAULT_HELP = {
        **GraphVecEnv.FAULT_HELP,
        "diverged_resets": "a world's state stopped being finite; it ended with reward 0 and was reset",
        "solver_overflows": "MuJoCo Warp's constraint or contact buffers were full and a world lost constraints for "
                            "a physics step: pass larger nconmax / njmax",
    }

    def __init__(self, task: str | LeggedTask = "Go1VelocityFlat-v0", num_envs: int = 1, device: str | None = None,
                 seed: int = 0, max_episode_steps: int | None = None, render_mode: str | None = None, **kwargs):
        base = get_legged_task(task)
        if max_episode_steps is not None:
            kwargs["episode_length_s"] = float(max_episode_steps) * base.decimation * base.timestep
        self.task = task = base.replace(**kwargs) if kwargs else base
        task.validate()
        if render_mode is not None:
            raise ValueError(f"render_mode={render_mode!r}: {task.name} draws through `warpgym play RUN --gif`")
        self.render_mode = None
        compiled, self.terrain = compile_task_scene(task)
        self.index = idx = resolve(task, compiled.mjm)
        self.sim = sim = MjwSim(compiled, num_envs, device, frame_skip=task.decimation, nconmax=task.nconmax,
                                njmax=task.njmax, contact_sensor_maxmatch=task.contact_sensor_maxmatch)
        self.num_envs = n = sim.num_envs
        self.device = sim.torch_device
        self.num_actions = a = sim.nu
        joints, feet = len(idx.joint_names), len(idx.foot_site)
        scan = 0 if task.height_scan is None else len(task.height_scan.offsets)
        self.dims = size = dims(task, idx, a)
        # each group's entries, term by term: (name, offset, size, what)
        self.layouts = {"policy": layout(task.policy_obs, size, f"{task.name}: policy_obs"),
                        "critic": layout(task.critic_obs, size, f"{task.name}: critic_obs")}
        self.num_obs = o = sum(n for *_, n, _ in self.layouts["policy"])
        self.num_critic_obs = c = sum(n for *_, n, _ in self.layouts["critic"])
        self.max_episode_steps = task.episode_length
        self.metadata = {**self.metadata, "render_fps": int(round(1.0 / (task.decimation * task.timestep)))}
        self.single_observation_space = spaces.Box(-np.inf, np.inf, (o,), np.float32)
        self.single_action_space = spaces.Box(-np.inf, np.inf, (a,), np.float32)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)

        dev, buf = sim.device, self._buf
        self.params, self.robot = kernel_structs(task, idx, dev)
        d = sim.d
        self._mj = view = MjLegged()
        view.qpos, view.qvel, view.ctrl = d.qpos, d.qvel, d.ctrl
        view.xpos, view.xquat, view.cvel, view.subtree_com = d.xpos, d.xquat, d.cvel, d.subtree_com
        view.site_xpos, view.sensordata, view.warm_start = d.site_xpos, d.sensordata, d.qacc_warmstart

        self._state = st = LeggedState()
        st.action, st.prev_action = buf((n, a)), buf((n, a))
        st.command, st.heading_target, st.command_kind = buf((n, 3)), buf(n), buf(n, wp.int32)
        st.command_time_left = buf(n)
        st.air_time, st.contact_time = buf((n, feet)), buf((n, feet))
        st.peak_height, st.foot_height = buf((n, feet)), buf((n, feet))
        st.collision_hits, st.encoder_bias = buf((n, NUM_GROUPS), wp.int32), buf((n, joints))
        st.step_count, st.fresh = buf(1, wp.int32), buf(n, wp.int32)
        st.scan, st.foot_clear = buf((n, max(scan, 1))), buf((n, feet))
        st.terrain_normal = wp.array(np.tile(np.float32([0.0, 0.0, 1.0]), (n, 1)), dtype=wp.vec3, device=dev)
        self._terrain_levels(seed)
        self._scans()
        self._episodes = ep = LeggedEpisodes()
        ep.length, ep.total_return, ep.errors = buf(n, wp.int32), buf(n), buf((n, 2))
        ep.ended_return, ep.ended_length, ep.ended_errors = buf(n), buf(n, wp.int32), buf((n, 2))
        ep.terms = buf((n, len(task.rewards)))
        self._critic, self._final_critic = buf((n, c)), buf((n, c))
        self._stagger = 0

        out = self._alloc_common(n, o, a, seed)
        self._tables(dev)
        self._startup()
        sim.after_substep = lambda: wp.launch(track_feet, dim=n, inputs=[self.params, self.robot, self._mj,
                                                                          self._state], device=dev)
        t = sim.to_torch
        self.actions = t(st.action)
        self.episode_steps = t(ep.length)
        done = t(out.done)
        terms = t(ep.terms)
        errors = t(ep.ended_errors)
        episode = {"r": t(ep.ended_return), "l": t(ep.ended_length), "error_vel_xy": errors[:, 0],
                   "error_vel_yaw": errors[:, 1], "_r": done, "_l": done}
        if self.terrain is not None:  # the level each ended episode's world moved to: training logs its mean
            episode["terrain_level"] = t(self._levels.level)
        so_far = {"r": t(ep.total_return), "l": t(ep.length)}
        self._expose({**{f"reward_{name}": terms[:, k] for k, name in enumerate(task.rewards)},
                      "episode": episode, "_episode": done, "episode_so_far": so_far,
                      "critic_obs": t(self._critic), "final_critic_obs": t(self._final_critic),
                      "command": t(st.command),
                      **({"terrain_level": t(self._levels.level)} if self.terrain is not None else {})})

    # ------------------------------------------------------------------ the task's tables of terms
    def _tables(self, dev: str) -> None:
        """The task's tables as its kernels take them (``warpgym.tasks.terms``), the state every term reads
        (``kernels.legged.params.LeggedEnv``), and the kernels made from the tables: the step's, the
        observation's, the reset's and the startup's."""
        task, joints, sim = self.task, self.index.joint_names, self.sim
        sim.per_world(*RANDOMISED_FIELDS, *DERIVED_FIELDS)
        self._model = m = MjLeggedModel()
        m.geom_friction, m.body_ipos = sim.m.geom_friction, sim.m.body_ipos
        m.body_ipos0 = wp.array(sim.mjm.body_ipos.astype(np.float32), dtype=wp.vec3, device=dev)
        Env = terms_state.LeggedEnv
        self._env = env = Env()
        env.p, env.r, env.d, env.m, env.st, env.t = self.params, self.robot, self._mj, m, self._state, self._levels
        self._rewards = compile_rewards(task.rewards, Env, joints, dev, f"{task.name}: rewards")
        self._terminations = compile_terminations(task.terminations, Env, joints, dev,
                                                  f"{task.name}: terminations")
        n = self.num_envs
        self._policy = compile_observations(task.policy_obs, "policy", Env, self.dims, joints, dev,
                                            task.observation_noise, f"{task.name}: policy_obs", n)
        self._critic_obs = compile_observations(task.critic_obs, "critic", Env, self.dims, joints, dev,
                                                task.observation_noise, f"{task.name}: critic_obs", n)
        self._events = compile_events(task.events, Env, joints, dev, n, f"{task.name}: events")
        self._timers = self._events["interval"].arrays
        self._timer_names = list(of_mode(task.events, "interval"))
        tables = self._rewards, self._terminations, self._policy, self._critic_obs, self._events["interval"]
        self._step_kernel, self._observe_kernel = step_kernels(*[x for t in tables for x in (t.func, t.params_type)])
        reset, startup = self._events["reset"], self._events["startup"]
        self._reset_kernel, self._startup_kernel = reset_kernels(reset.func, reset.params_type, startup.func,
                                                                 startup.params_type)
        self.state_keys = self.BASE_STATE_KEYS + tuple(f"{name}_time_left" for name in self._timer_names)

    def _observe_inputs(self) -> list:
        return [self._policy.params, self._policy.arrays, self._critic_obs.params, self._critic_obs.arrays]

    def _launch_observe(self) -> None:
        wp.launch(self._observe_kernel, dim=self.num_envs,
                  inputs=[self._env, self._rng_state, *self._observe_inputs(), self._out.obs, self._critic],
                  device=self.sim.device)

    # ------------------------------------------------------------------ rough ground
    def curriculum(self) -> dict[str, torch.Tensor]:
        """The curriculum's state (agents.protocol): the mean terrain level over every world, as mjlab logs its
        ``Curriculum/terrain_levels/mean``; nothing on the flat floor."""
        if self.terrain is None:
            return {}
        return {"terrain_level": self.info["terrain_level"].float().mean()}

    def _terrain_levels(self, seed: int) -> None:
        """Each world's level, kind and start on the generated ground (``TerrainLevels``); on the flat floor one
        start at the origin and no bound."""
        task, n, dev = self.task, self.num_envs, self.sim.device
        t = self._levels = TerrainLevels()
        if self.terrain is None:
            levels, kinds, origins = np.zeros(n, np.int32), np.zeros(n, np.int32), np.zeros((1, 1, 3), np.float32)
            t.half_x = t.half_y = 1.0e30
        else:
            levels, kinds = start_levels(self.terrain, n, task.max_init_terrain_level, np.random.default_rng(seed))
            origins = self.terrain.origins.astype(np.float32)
            t.half_x, t.half_y = bounds(self.terrain, task.terrain_margin)
        t.origins = wp.array(origins, dtype=wp.vec3, device=dev)
        t.level = wp.array(levels, dtype=wp.int32, device=dev)
        t.kind = wp.array(kinds, dtype=wp.int32, device=dev)
        t.origin = wp.array(origins[levels, kinds], dtype=wp.vec3, device=dev)
        t.patch_length = float(self.terrain.grid.size[0]) if self.terrain is not None else 1.0e30
        t.episode_s = float(task.episode_length_s)

    def _scans(self) -> None:
        """The height scan under the root body and the ring under each foot, cast by MuJoCo Warp."""
        task, sim, idx = self.task, self.sim, self.index
        self._height_scan = self._foot_scan = self._caster = None
        patterns = [p for p in (task.height_scan, task.foot_scan) if p is not None]
        if not patterns:
            return
        groups = sorted({g for p in patterns for g in p.groups})
        self._caster = RayCaster(sim.mjm, sim.m, sim.d, tuple(groups), device=sim.device)
        if task.height_scan is not None:
            p = task.height_scan
            root = np.array([idx.root_body])
            self._height_scan = Scan(ScanFrames("body", root, root), p.array(), p.direction, p.alignment,
                                     p.max_distance, num_envs=self.num_envs, device=sim.device)
            self._normal_picks = wp.array(normal_picks(self._height_scan.num_rays), dtype=wp.int32, device=sim.device)
        if task.foot_scan is not None:
            p = task.foot_scan
            self._foot_scan = Scan(ScanFrames("site", idx.foot_site, idx.foot_body), p.array(), p.direction,
                                   p.alignment, p.max_distance, num_envs=self.num_envs, device=sim.device)

    def _sense(self) -> None:
        """mjlab's sense pass after the forward pass: the scans cast, read into the task's state."""
        if self._caster is None:
            return
        st, n, dev = self._state, self.num_envs, self.sim.device
        scans = [s for s in (self._height_scan, self._foot_scan) if s is not None]
        self._caster.sense(*scans)
        if self._height_scan is not None:
            self._height_scan.heights(st.scan)
            # the ground's normal under the base, for terms that measure tilt against it (the rough Go1's upright)
            wp.launch(fit_ground_normal, dim=n, inputs=[self._height_scan.s, self._normal_picks],
                      outputs=[st.terrain_normal], device=dev)
        if self._foot_scan is not None:
            self._foot_scan.clearance(st.foot_clear)

    # ------------------------------------------------------------------ the startup events
    def _startup(self) -> None:
        """mjlab's startup events, per world (the legged tasks': foot friction, the centre of mass offset, the
        encoder bias); then the model constants that depend on them."""
        sim = self.sim
        wp.launch(self._startup_kernel, dim=self.num_envs,
                  inputs=[self._env, self._rng_state, self._events["startup"].params], device=sim.device)
        sim.set_const()
        wp.launch(_advance, dim=1, inputs=[self._rng_state], device=sim.device)

    # ------------------------------------------------------------------ device work
    def _launch_step(self) -> None:
        sim, n, dev = self.sim, self.num_envs, self.sim.device
        wp.launch(count_step, dim=1, inputs=[self._state], device=dev)
        wp.launch(apply_legged_actions, dim=n, inputs=[self._actions_in, self.robot, self._state],
                  outputs=[sim.d.ctrl, self._nan_count], device=dev)
        # the step's last forward pass (after its resets, or write_state's) is the first physics step's positions
        # and velocities: only the controls changed since
        sim.simulate(after_forward=True)
        wp.launch(self._step_kernel, dim=n,
                  inputs=[self._env, self._rng_state, self._rewards.params, self._rewards.arrays,
                          self._terminations.params, *self._observe_inputs(), self._events["interval"].params,
                          self._timers, self._episodes, self._out, self._final_critic], device=dev)
        self._finish_step()

    def _launch_reset(self, force_all: int) -> None:
        sim, n, dev = self.sim, self.num_envs, self.sim.device
        if self.terrain is not None:  # mjlab's curriculum runs first in its reset
            wp.launch(move_levels, dim=n, inputs=[self._levels, self.robot, self._mj, self._state, force_all,
                                                  self._rng_state, self._out], device=dev)
        wp.launch(self._reset_kernel, dim=n, inputs=[self._env, force_all, self._stagger, self._rng_state,
                                                     self._events["reset"].params, self._timers, self._episodes,
                                                     self._out], device=dev)
        sim.forward()
        self._sense()
        wp.launch(update_commands, dim=n, inputs=[self.params, self.robot, force_all, self._rng_state, self._out.done,
                                                  self._mj, self._state, self._episodes], device=dev)
        self._launch_observe()

    # ------------------------------------------------------------------ the task's state (Tensor API)
    # and, per interval event, "<name>_time_left" (the push_robot event's: push_robot_time_left)
    BASE_STATE_KEYS = ("qpos", "qvel", "warm_start", "action", "prev_action", "command", "heading_target",
                       "command_kind", "command_time_left", "air_time", "contact_time", "peak_height", "foot_height",
                       "encoder_bias", "length", "errors", "foot_friction", "body_ipos", "terrain_level",
                       "terrain_kind", "env_origin", "terrain_normal")

    def _state_views(self) -> dict[str, torch.Tensor]:
        """Writable torch views of everything a world carries from step to step: MuJoCo's state, the task's
        (command, timers, contact times, action history; on rough ground its level, kind, start and the ground's
        normal under the base from the last scan), the interval events' timers and the randomised model fields."""
        t, st, d, m, ep, lv = self.sim.to_torch, self._state, self.sim.d, self.sim.m, self._episodes, self._levels
        left = t(self._timers.left)
        return {"qpos": t(d.qpos), "qvel": t(d.qvel), "warm_start": t(d.qacc_warmstart), "action": t(st.action),
                "prev_action": t(st.prev_action), "command": t(st.command), "heading_target": t(st.heading_target),
                "command_kind": t(st.command_kind), "command_time_left": t(st.command_time_left),
                **{f"{name}_time_left": left[:, k] for k, name in enumerate(self._timer_names)},
                "air_time": t(st.air_time), "contact_time": t(st.contact_time),
                "peak_height": t(st.peak_height), "foot_height": t(st.foot_height), "encoder_bias": t(st.encoder_bias),
                "length": t(ep.length), "errors": t(ep.errors), "geom_friction": t(m.geom_friction),
                "body_ipos": t(m.body_ipos), "terrain_level": t(lv.level), "terrain_kind": t(lv.kind),
                "env_origin": t(lv.origin), "terrain_normal": t(st.terrain_normal)}

    def state(self) -> dict[str, torch.Tensor]:
        """A copy of every world's state (``state_keys``: ``BASE_STATE_KEYS`` and a timer per interval event;
        ``foot_friction`` is the foot geoms' (N, G, 3)), and the env's step count."""
        views = self._state_views()
        out = {k: v.clone() for k, v in views.items() if k != "geom_friction"}
        out["foot_friction"] = views["geom_friction"][:, torch.as_tensor(self.index.foot_geoms).long()].clone()
        out["step_count"] = int(self.sim.to_torch(self._state.step_count)[0])
        return out

    def write_state(self, state: dict) -> None:
        """Write worlds' state (any of ``state_keys``, each for every world, and ``step_count``), as ``state()``
        returns it, or as mjlab's env holds it (tests/test_legged_judge.py starts both from one state). A new
        ``body_ipos`` recomputes the model constants derived from it; the next step starts from this state."""
        unknown = sorted(set(state) - set(self.state_keys) - {"step_count"})
        if unknown:
            raise ValueError(f"write_state: no state {unknown}: the keys are {list(self.state_keys)} and step_count")
        views = self._state_views()
        for key, value in state.items():
            if key == "step_count":
                self.sim.to_torch(self._state.step_count).fill_(int(value))
                continue
            value = torch.as_tensor(value, device=self.device)
            if key == "foot_friction":
                ids = torch.as_tensor(self.index.foot_geoms, device=self.device).long()
                views["geom_friction"][:, ids] = value.to(torch.float32)
                continue
            view = views[key]
            if tuple(value.shape) != tuple(view.shape):
                raise ValueError(f"write_state: {key} has shape {tuple(value.shape)}, this env's is {tuple(view.shape)}")
            view.copy_(value.to(view.dtype))
        cuda = self.sim.device != "cpu"
        if cuda:  # the writes above are torch's, on its stream; set_const and forward run on Warp's
            torch.cuda.synchronize(self.device)
        if "body_ipos" in state:
            self.sim.set_const()
        # the frames, contacts and sensors of the state written: the next step's first physics step starts from them
        self.sim.forward()
        if cuda:  # not a hot path: the state is whole before anything reads it, on either stream
            wp.synchronize_device(self.sim.device)

    def observe(self):
        """MuJoCo's forward pass and both observations of the state as it is (one written by ``write_state``,
        say), without a step or any draw: the policy's observation, and the critic's in the info."""
        def run():
            self.sim.forward()
            self._sense()
            self._launch_observe()

        self.sim.launch(None, run)
        return self.obs, {"critic_obs": self.info["critic_obs"]}

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, info = super().reset(seed=seed, options=options)
        return obs, {"critic_obs": self.info["critic_obs"]}

    def stagger_episodes(self):
        """Reset every world with its elapsed steps drawn uniformly in [0, max_episode_steps) (rsl_rl's
        ``init_at_random_ep_len``, which mjlab's training uses): the time limits then fall apart rather than all
        at once. Returns the first observations, as ``reset()`` does."""
        self._stagger = 1
        try:
            self._reset_all()
        finally:
            self._stagger = 0
        return self.obs, {"critic_obs": self.info["critic_obs"]}

    def __repr__(self) -> str:
        return f"LeggedVecEnv({self.task.name}, num_envs={self.num_envs}, device={self.sim.device!r})"


class LeggedEnv(SingleEnv):
    """One world of a legged velocity task (``gym.make("warpgym/Go1VelocityFlat-v0")``): numpy in and out, the
    reward terms in ``info``, the critic's observation in ``info["critic_obs"]`` and the command in
    ``info["command"]``."""

    vec_class = LeggedVecEnv
    metadata = LeggedVecEnv.metadata

    def __init__(self, task="Go1VelocityFlat-v0", device: str = "cpu", seed: int = 0, render_mode=None, **kwargs):
        super().__init__(task, device, seed, render_mode, **kwargs)

    def _extra(self, info: dict, done: bool) -> dict:
        critic = info["final_critic_obs" if done else "critic_obs"]
        return {"critic_obs": critic[0].cpu().numpy().copy(), "command": info["command"][0].cpu().numpy().copy()}


@wp.kernel
def _advance(rng_state: wp.array[wp.int32]):
    rng_state[1] = rng_state[1] + 1
