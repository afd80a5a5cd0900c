"""Collect rollouts (agents.collect) and update the policy, everything on the env's device.

The observation normaliser learns once per rollout, batched over all its steps. The host reads the
device once per iteration, to log, one iteration late: the statistics of iteration k are copied out
while iteration k+1 runs, so the GPU never waits on logging.
"""

from __future__ import annotations

import torch

from agents.actor_critic import ActorCritic
from agents.background_eval import BackgroundEvaluation
from agents.collect import CAPTURES, Collector
from agents.config import Config
from agents.loop import TrainingLoop
from agents.normalizer import RunningMeanStd
from agents.overlap import RolloutPipeline
from agents.ppo import PPO
from agents.protocol import env_spec
from agents.rollout import EpisodeTracker
from agents.storage import RolloutStorage


class OnPolicyRunner(TrainingLoop):
    UPDATE_PHASE = "PPO update"
    NONFINITE_HELP = "the env returned NaN/inf observations or rewards; PPO trained on them"

    def __init__(self, env, cfg: Config, run_dir: str | None = None, eval_env=None,
                 start_time: float | None = None, print_fn=print, profile: bool = False, cuda_graph: bool = True,
                 rollout_graph: str = "step", eval_recorder=None):
        if rollout_graph not in CAPTURES:
            raise ValueError(f"rollout_graph={rollout_graph!r}: choose one of {CAPTURES} (agents.collect)")
        cfg = cfg.validated()
        self.init_loop(env, cfg, run_dir, eval_env, start_time, print_fn, profile, eval_recorder)
        spec = self.spec
        # this process's part of every mini-batch, as Config.multi_gpu divides the work (agents.data_parallel)
        self.num_minibatches = cfg.check_batch(spec.num_envs, self.workers.size)
        self.horizon = cfg.process_horizon(self.workers.size)  # this process's steps per iteration
        torch.manual_seed(cfg.seed)
        if self.device.type == "cuda" and cfg.tf32:
            # TF32 matmuls: the policy's layers run on tensor cores; PPO does not notice the precision
            torch.backends.cuda.matmul.allow_tf32 = True
        self.policy = ActorCritic(spec.num_obs, spec.num_actions, cfg.net_dims, cfg.activation,
                                  cfg.init_noise_std, spec.num_critic_obs).to(self.device)
        self.normalizer = RunningMeanStd(spec.num_obs, cfg.obs_clip, until=cfg.normalize_until).to(self.device)
        # an asymmetric actor-critic's critic observation has statistics of its own (rsl_rl's critic normaliser)
        self.critic_normalizer = (RunningMeanStd(spec.num_critic_obs, cfg.obs_clip, until=cfg.normalize_until)
                                  .to(self.device) if spec.num_critic_obs else None)
        if cfg.stagger_episodes and not callable(getattr(env, "stagger_episodes", None)):
            raise ValueError(f"stagger_episodes=True: {type(env).__name__} has no stagger_episodes(); train it with "
                             "stagger_episodes=False")
        # every process starts from rank 0's weights, then explores with its own noise
        self.workers.broadcast_(list(self.policy.parameters()) + list(self._normalizer_buffers()))
        torch.manual_seed(self.rank_seed(0))
        self.ppo = PPO(self.policy, cfg, self.device, cuda_graph=cuda_graph, workers=self.workers)
        self.storage = RolloutStorage(self.horizon, spec.num_envs, spec.num_obs, spec.num_actions, self.device,
                                      spec.num_critic_obs)
        self.episodes = EpisodeTracker(self.horizon, spec.num_envs, self.device)
        self.pipeline = RolloutPipeline(self.policy, self.storage, self.device) if cfg.overlap else None
        if cfg.eval_background and self.eval_recorder is not None:
            self.print("eval_background: the evaluation video draws every step of it, so the evaluations stay "
                       "synchronous (record no video to run them beside training)")
        elif cfg.eval_background and self.eval_env is not None:
            eval_spec = env_spec(self.eval_env)
            self.background = BackgroundEvaluation(
                self.eval_env, self.policy, self.normalizer, cfg.normalize_obs, eval_spec.max_episode_steps,
                self.device, cuda_graph and eval_spec.graph_capturable, self.print)
        # Only an env that declares it (agents.protocol) is captured; the normaliser update stays
        # outside the graph, since across processes it all-reduces.
        capturable = cuda_graph and self.device.type == "cuda" and spec.graph_capturable
        self.collector = Collector(env, cfg, self.acting_policy, self.normalize, self.storage, self.episodes,
                                   self.device, rollout_graph if capturable else "off", self.print,
                                   self.normalize_critic)
        if self.background is not None:  # its steps go one beside each of the rollout's (agents.background_eval)
            self.collector.beside = self.background.beside
        # and the learner's own: non-finite observation or reward entries that reached the rollout
        self.count_nonfinite(self.collector.nonfinite)

    @property
    def capture(self) -> str:
        """The capture the rollouts have (agents.collect): "off" where the device cannot capture or a capture failed."""
        return self.collector.capture

    # ------------------------------------------------------------------ pieces

    def _normalizer_buffers(self) -> list[torch.Tensor]:
        both = [self.normalizer] + ([self.critic_normalizer] if self.critic_normalizer is not None else [])
        return [b for n in both for b in n.buffers()]

    @property
    def acting_policy(self) -> ActorCritic:
        """The weights rollouts are drawn with: the policy, or its behaviour copy (Config.overlap)."""
        return self.policy if self.pipeline is None else self.pipeline.behaviour

    @torch.no_grad()
    def collect(self) -> None:
        """One rollout of this process's ``horizon`` steps (agents.collect), then the observation normaliser
        learns from it."""
        if self.collector.last_raw_obs is None:
            obs, critic = self.collector.start(self.cfg.stagger_episodes)
            self.normalizer.update(obs, self.workers)
            if critic is not None:
                self.critic_normalizer.update(critic, self.workers)
        self.timer.start()
        self._old_log_std = self.acting_policy.log_std.detach().clone()  # the noise the rollout is drawn with
        self.collector.rollout(self.timer)
        self.clock.mark("collect")
        self._learn_normalizer()

    def _learn_normalizer(self) -> None:
        if self.cfg.normalize_obs:
            self.normalizer.update(self.storage.raw_obs.flatten(0, 1), self.workers)
            if self.critic_normalizer is not None:
                self.critic_normalizer.update(self.storage.raw_critic_obs.flatten(0, 1), self.workers)
        self.clock.mark("normalizer")
        self.timer.lap("normaliser update")

    def update(self) -> dict:
        if self.pipeline is None:
            return self.ppo.update(self.storage, self._old_log_std, self.num_minibatches)
        return self.ppo.update(self.pipeline.trained, self.pipeline.trained_log_std, self.num_minibatches, lagged=True)

    def iterate(self) -> dict:
        """Collect a rollout and update the policy: one after the other, or with ``Config.overlap``
        rollout k collected by the weights of update k-1 while PPO learns from rollout k-1."""
        pipe = self.pipeline
        if pipe is None:
            self.collect()
            return self.update()
        if not pipe.pending:  # at start or resume: a first rollout, for the update to learn from
            pipe.sync(self.policy)
            self.collect()
            pipe.hand_over(self.storage, self._old_log_std)
            self.samples += self._per_iter
        pipe.sync(self.policy)
        side_by_side = pipe.stream is not None and self.collector.graph is not None and not self.timer.enabled
        if side_by_side:
            main = torch.cuda.current_stream(self.device)
            self._old_log_std = pipe.behaviour.log_std.detach().clone()
            pipe.stream.wait_stream(main)  # the behaviour weights and the normaliser are written
            with torch.cuda.stream(pipe.stream):
                self.collector.replay()
            stats = self.update()
            self.clock.mark("update")
            main.wait_stream(pipe.stream)
            self.clock.mark("collect")  # the part of the rollout the update did not hide
            with torch.no_grad():
                self._learn_normalizer()
        else:
            self.collect()
            stats = self.update()
        pipe.hand_over(self.storage, self._old_log_std)
        return stats

    def before_iteration(self, progress: float) -> None:
        if self.cfg.anneal_lr:
            self.ppo.lr_scale.fill_(1.0 - progress)

    def close(self) -> None:
        """Free the CUDA graphs (before ``destroy_process_group``: see ``PPO.release_graph``)."""
        self.ppo.release_graph()
        self.collector.graph = None
        if self.background is not None:
            self.background.close()
        super().close()

    # ------------------------------------------------------------------ checkpoints
    def state_dict(self) -> dict:
        return {
            **self.loop_state(),
            "policy": self.policy.state_dict(), **self.normalizer_states(),
            "optimizer": self.ppo.optimizer.state_dict(), "lr": self.ppo.lr.item(), "lr_free": self.ppo.lr_free.item(),
        }

    def load(self, path: str, resume: bool = True) -> None:
        """Load a checkpoint that rank 0 can read (other processes, on other machines, get its bytes).

        With ``resume``, the run goes on from it: counters, optimiser, learning rate and random state,
        and the metrics logged after it are dropped, since they will be logged again. Any number of
        processes may resume a run; every process but rank 0 draws new exploration noise."""
        ckpt = self.read_checkpoint(path)
        self.policy.load_state_dict(ckpt["policy"])
        self.load_normalizers(ckpt)
        if resume:
            self.ppo.optimizer.load_state_dict(ckpt["optimizer"])
            self.ppo.lr.fill_(ckpt["lr"])
            self.ppo.lr_free.fill_(ckpt.get("lr_free", ckpt["lr"]))
            if self.pipeline is not None:  # its rollout was not saved: the next iteration collects one first
                self.pipeline.pending = False
            self.resume_loop(ckpt)
