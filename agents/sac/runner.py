"""Off-policy training on a GPU vector env: every env step acts with the policy's sample, stores the transition in
the device replay (agents.sac.replay) and runs that step's updates (agents.sac.learner). An iteration is
``steps_per_iteration`` such steps, then one row logged as PPO's are (agents.loop).

On CUDA, after ``learning_starts`` steps and one eager update (the optimisers' state), a whole env step (the
policy, the env's step where the env is capturable, the replay, the updates) is captured as one CUDA graph and
every later step replays it; an env that cannot be captured steps eagerly beside its captured updates.

The replay is not saved with a checkpoint (at 4096 envs it holds GBs): a resumed run collects ``learning_starts``
steps again before it updates.
"""

from __future__ import annotations

import torch

from agents.loop import TrainingLoop
from agents.protocol import critic_obs_of
from agents.normalizer import RunningMeanStd
from agents.rollout import EpisodeTracker
from agents.sac.config import SACConfig
from agents.sac.learner import SAC
from agents.sac.networks import DistributionalCritic, SquashedGaussianPolicy
from agents.sac.relabel import goal_spec
from agents.sac.replay import ReplayBuffer

CAPTURES = ("step", "update", "off")


class OffPolicyRunner(TrainingLoop):
    UPDATE_PHASE = "env steps and SAC updates"

    def __init__(self, env, cfg: SACConfig, run_dir: str | None = None, eval_env=None,
                 start_time: float | None = None, print_fn=print, profile: bool = False, cuda_graph: bool = True,
                 eval_recorder=None):
        cfg = cfg.validated()
        self.init_loop(env, cfg, run_dir, eval_env, start_time, print_fn, profile, eval_recorder)
        if self.workers.size > 1:
            raise ValueError(f"agent {cfg.agent} trains in one process; this run has {self.workers.size} "
                             "(torchrun): train it with python -m warpgym train, or PPO on several GPUs")
        spec, device = self.spec, self.device
        self.horizon = cfg.steps_per_iteration
        torch.manual_seed(cfg.seed)
        if device.type == "cuda" and cfg.tf32:
            torch.backends.cuda.matmul.allow_tf32 = True
        self.policy = SquashedGaussianPolicy(spec.num_obs, spec.num_actions, cfg.actor_dims, cfg.layer_norm,
                                             cfg.log_std_min, cfg.log_std_max).to(device)
        critic_obs = spec.num_critic_obs or spec.num_obs
        self.critic = DistributionalCritic(critic_obs, spec.num_actions, cfg.critic_dims, cfg.num_atoms, cfg.v_min,
                                           cfg.v_max, cfg.layer_norm, cfg.num_critics).to(device)
        self.normalizer = RunningMeanStd(spec.num_obs, cfg.obs_clip).to(device)
        self.critic_normalizer = (RunningMeanStd(spec.num_critic_obs, cfg.obs_clip).to(device)
                                  if spec.num_critic_obs else None)
        self.goals = goal_spec(env, spec.max_episode_steps)
        if self.goals is not None and cfg.n_step > 1:
            raise ValueError(f"n_step={cfg.n_step}: goal relabelling recomputes one step's reward; train "
                             f"{type(env).__name__} with n_step=1")
        self.buffer = ReplayBuffer(cfg.buffer_size, spec.num_envs, spec.num_obs, spec.num_actions, device,
                                   spec.num_critic_obs, self.goals.size if self.goals else 0)
        self.sac = SAC(self.policy, self.critic, cfg, self.buffer, spec.num_actions, device, self.normalize,
                       self.normalize_critic, self.goals)
        self.episodes = EpisodeTracker(self.horizon, spec.num_envs, device)
        self.dones = torch.zeros(self.horizon, spec.num_envs, device=device)
        self.step_index = torch.zeros(1, dtype=torch.long, device=device)
        self.nonfinite = torch.zeros((), dtype=torch.int64, device=device)
        self.count_nonfinite(self.nonfinite)
        cuda = cuda_graph and device.type == "cuda"
        self._capture = ("step" if getattr(env, "graph_capturable", False) else "update") if cuda else "off"
        self._graph: torch.cuda.CUDAGraph | None = None
        self.env_steps = 0  # steps taken by this process (the replay's fill), on the host
        self.updated_steps = 0  # steps whose updates ran
        self.last_raw_obs: torch.Tensor | None = None
        self.last_raw_critic: torch.Tensor | None = None

    @property
    def capture(self) -> str:
        """What one step's CUDA graph holds: "step" (the env's step too), "update" (the updates alone) or "off"."""
        return self._capture

    # ------------------------------------------------------------------ steps
    def start(self) -> None:
        obs, info = self.env.reset()
        self.last_raw_obs = obs.clone()
        if self.spec.num_critic_obs:
            self.last_raw_critic = critic_obs_of(info, self.env).clone()

    @torch.no_grad()
    def act_and_store(self) -> None:
        """One env step into the replay: the same launches every step (device-held indices), so capturable."""
        raw, critic = self.last_raw_obs, self.last_raw_critic
        if self.cfg.normalize_obs:
            self.normalizer.update(raw)
            if critic is not None:
                self.critic_normalizer.update(critic)
        actions, _ = self.policy.sample(self.normalize(raw))
        next_obs, reward, terminated, truncated, info = self.env.step(actions)
        done = terminated | truncated
        true_next = torch.where(done[:, None], info["final_obs"], next_obs)
        next_critic = None
        if critic is not None:
            next_critic = torch.where(done[:, None], info["final_critic_obs"], info["critic_obs"])
        achieved = info["achieved_goal"] if self.goals is not None else None
        self.buffer.add(raw, actions, reward, true_next, terminated, done, critic, next_critic, achieved)
        self.episodes.record(self.step_index, reward, done, info)
        self.dones.index_copy_(0, self.step_index, done.float()[None])
        self.step_index += 1
        self.nonfinite += (~torch.isfinite(next_obs)).sum() + (~torch.isfinite(reward)).sum()
        raw.copy_(next_obs)  # after the replay has its copy
        if critic is not None:
            critic.copy_(info["critic_obs"])

    def _step_and_update(self) -> None:
        self.act_and_store()
        self.sac.update()

    def _capture_step(self) -> None:
        """The graph of one step (the env's too under "step"); a failure leaves the steps eager."""
        graph = torch.cuda.CUDAGraph()
        try:
            with torch.cuda.graph(graph, capture_error_mode="thread_local"):
                if self._capture == "step":
                    self._step_and_update()
                else:
                    self.sac.update()
        except RuntimeError as e:
            self.print(f"warning: capturing the SAC step as a CUDA graph failed ({e}); stepping eagerly")
            self._capture = "off"
            return
        self._graph = graph
        # the capture recorded the step's launches without running them: run the step it stood for
        self._replay()

    def _replay(self) -> None:
        if self._capture == "update":
            self.act_and_store()
        self._graph.replay()

    def one_step(self) -> None:
        if self.env_steps < self.cfg.learning_starts:
            self.act_and_store()  # the replay fills before any update
        elif self._graph is not None:
            self._replay()
        elif self._capture != "off" and self.updated_steps > 0:
            self._capture_step()
        elif self._capture != "off":
            # the first update eagerly, on a side stream: CUDA graphs want the optimisers' state made and kernels warm
            main, side = torch.cuda.current_stream(self.device), torch.cuda.Stream(self.device)
            side.wait_stream(main)
            with torch.cuda.stream(side):
                self._step_and_update()
            main.wait_stream(side)
        else:
            self._step_and_update()
        if self.env_steps >= self.cfg.learning_starts:
            self.updated_steps += 1
        self.env_steps += 1

    def iterate(self) -> dict:
        if self.last_raw_obs is None:
            self.start()
        self.timer.start()
        for _ in range(self.horizon):
            self.one_step()
        self.episodes.end_rollout(self.dones)
        self.step_index.zero_()
        return self.sac.take_stats()

    def close(self) -> None:
        self._graph = None
        super().close()

    # ------------------------------------------------------------------ checkpoints
    def state_dict(self) -> dict:
        return {
            **self.loop_state(),
            "policy": self.policy.state_dict(), "critic": self.critic.state_dict(),
            "critic_target": self.sac.critic_target.state_dict(), "log_alpha": self.sac.log_alpha.detach().clone(),
            **self.normalizer_states(), "optimizer": self.sac.optimizer_states(),
        }

    def load(self, path: str, resume: bool = True) -> None:
        """The checkpoint's weights and normalisers; with ``resume`` its optimisers, temperature and counters too,
        the replay refilled from scratch (module docstring)."""
        ckpt = self.read_checkpoint(path)
        if ckpt["config"].get("agent") != self.cfg.agent:
            raise ValueError(f"checkpoint {path} was trained by {ckpt['config'].get('agent')!r}, not "
                             f"{self.cfg.agent!r}: resume it with its own learner")
        self.policy.load_state_dict(ckpt["policy"])
        self.critic.load_state_dict(ckpt["critic"])
        self.sac.critic_target.load_state_dict(ckpt["critic_target"])
        self.load_normalizers(ckpt)
        if resume:
            with torch.no_grad():
                self.sac.log_alpha.copy_(ckpt["log_alpha"])
            self.sac.load_optimizer_states(ckpt["optimizer"])
            self.resume_loop(ckpt)
