"""Rollouts: the acting policy steps the env into the rollout storage, then the bootstrap and GAE.

Per env step there is no host synchronisation and little Python: the step's tensors are copied
into the storage at a step index held on the device, and what can wait (truncation bootstraps,
GAE, episode statistics) runs once per rollout, batched over all steps.

On CUDA the second rollout is captured as CUDA graphs and every later one replays them; the first
runs eagerly and warms up every kernel the capture records. Two ways to capture (``capture``):

- ``"step"``: one env step (policy, env, storage writes) is captured once and replayed
  ``horizon_len`` times, then the bootstrap and GAE as a second graph. The capture records one
  step's launches: a MuJoCo Warp step launches hundreds of kernels per physics step, and recording
  every step of a rollout costs seconds of each start (docs/history.md, "The step capture against the
  whole rollout's").
- ``"rollout"``: all ``horizon_len`` steps unrolled into one graph, replayed once.

Both replay the launches of the eager rollout in its order, so all three give the same numbers up to
MuJoCo Warp's float atomics (tests/test_cuda.py holds the tolerances).
"""

from __future__ import annotations

from typing import Callable

import torch

from agents.actor_critic import ActorCritic
from agents.config import Config
from agents.profiling import PhaseTimer
from agents.protocol import critic_obs_of
from agents.rollout import EpisodeTracker
from agents.storage import RolloutStorage, compute_gae

CAPTURES = ("step", "rollout", "off")


class WholeRollout:
    """A rollout captured as one graph: nothing runs between its steps, so ``replay`` cannot call ``beside``
    there (a background evaluation queues its steps after it instead: agents/background_eval.py)."""

    def __init__(self, graph: torch.cuda.CUDAGraph):
        self.graph = graph

    def replay(self, beside: Callable[[], None] | None = None) -> None:
        self.graph.replay()


class StepGraphs:
    """The step's graph ``horizon`` times, then the finishing graph: a rollout, as ``replay()`` of a
    rollout captured whole gives it."""

    def __init__(self, step: torch.cuda.CUDAGraph, finish: torch.cuda.CUDAGraph, horizon: int):
        self.step, self.finish, self.horizon = step, finish, horizon

    def replay(self, beside: Callable[[], None] | None = None) -> None:
        for _ in range(self.horizon):
            self.step.replay()
            if beside is not None:
                beside()
        self.finish.replay()


def capture_rollout(capture: str, step: Callable[[], None], finish: Callable[[], None], horizon: int,
                    device: torch.device):
    """``horizon`` calls of ``step`` and one of ``finish`` captured (``capture``: "step" or "rollout"), as an
    object whose ``replay()`` runs them. Nothing runs while capturing."""
    if capture not in ("step", "rollout"):
        raise ValueError(f"capture {capture!r}: choose 'step' or 'rollout'")
    with torch.cuda.device(device):
        if capture == "rollout":
            graph = torch.cuda.CUDAGraph()
            # thread_local: a watchdog thread (NCCL's) may query events while this thread captures
            with torch.cuda.graph(graph, capture_error_mode="thread_local"):
                for _ in range(horizon):
                    step()
                finish()
            return WholeRollout(graph)
        one, last = torch.cuda.CUDAGraph(), torch.cuda.CUDAGraph()
        with torch.cuda.graph(one, capture_error_mode="thread_local"):
            step()
        # one pool: the two always replay in the order they were captured, never at once
        with torch.cuda.graph(last, pool=one.pool(), capture_error_mode="thread_local"):
            finish()
        return StepGraphs(one, last, horizon)


class Collector:
    """Fills ``storage`` with rollouts of ``env`` drawn by ``policy`` (always this object: a captured
    graph reads its weights by address). The normalisers are frozen during a rollout. Where the storage keeps a
    critic observation (an asymmetric actor-critic), values are taken of the env's ``info["critic_obs"]``,
    normalised by ``normalize_critic``."""

    def __init__(self, env, cfg: Config, policy: ActorCritic, normalize: Callable[[torch.Tensor], torch.Tensor],
                 storage: RolloutStorage, episodes: EpisodeTracker, device: torch.device, capture: str,
                 print_fn=print, normalize_critic: Callable[[torch.Tensor], torch.Tensor] | None = None):
        self.env, self.cfg, self.policy, self.normalize = env, cfg, policy, normalize
        self.normalize_critic = normalize_critic
        self.storage, self.episodes, self.device, self.capture = storage, episodes, device, capture
        self.print = print_fn
        self.graph = None  # a CUDAGraph or StepGraphs, once captured
        # work of another stream's launched after each of the rollout's steps, eager or replayed (the background
        # evaluation's): a replay of a long graph of MuJoCo Warp steps holds the host until most of it has run, so
        # work queued after it mostly runs after it, while one step's graph returns at once (docs/history.md,
        # "Walker2d-v5's evaluations"). Never captured into the rollout's graphs; a rollout captured whole has no
        # steps to launch it between.
        self.beside: Callable[[], None] | None = None
        self.eager_rollouts = 0
        self.step_index = torch.zeros(1, dtype=torch.long, device=device)
        self.last_raw_obs: torch.Tensor | None = None  # the env's latest observation, not yet acted on
        self.last_raw_critic: torch.Tensor | None = None  # ... and the critic's (asymmetric actor-critic)
        # non-finite observation or reward entries that reached the rollout (agents.protocol's faults)
        self.nonfinite = torch.zeros((), dtype=torch.int64, device=device)

    def start(self, stagger: bool = False) -> tuple[torch.Tensor, torch.Tensor | None]:
        """Reset the env (``stagger``: with its episodes' elapsed steps spread, ``stagger_episodes``); its first
        observations, the policy's and the critic's (None when the critic reads the policy's)."""
        obs, info = self.env.stagger_episodes() if stagger else self.env.reset()
        self.last_raw_obs = obs.clone()
        if self.storage.critic_obs is not None:
            self.last_raw_critic = critic_obs_of(info, self.env).clone()
        return self.last_raw_obs, self.last_raw_critic

    def rollout(self, timer: PhaseTimer) -> None:
        """One rollout of the storage's horizon (this process's steps): replayed, captured (the second) or eager."""
        if self.graph is not None:
            self.replay()
            timer.lap("collect: rollout graph (policy, env step, storage, GAE)")
        elif self.capture != "off" and self.eager_rollouts > 0:
            self.graph = self._capture()
            if self.graph is not None:
                self.replay()
            else:
                self.run_eagerly(timer)
            timer.lap("collect: rollout graph capture")
        else:
            self.run_eagerly(timer)
            self.eager_rollouts += 1

    def replay(self) -> None:
        """The captured rollout, with ``beside`` after each step where it was captured step by step."""
        self.graph.replay(self.beside)

    def _capture(self):
        timer = PhaseTimer(self.device)  # never synchronises: a synchronisation would break the capture
        try:
            return capture_rollout(self.capture, lambda: self.step(timer), lambda: self.finish(timer),
                                   self.storage.horizon, self.device)
        except RuntimeError as e:
            # Nothing ran during the failed capture; the rollouts go on eagerly, a little slower.
            self.capture = "off"
            self.print(f"warning: capturing the rollout as a CUDA graph failed ({e}); collecting eagerly")
            return None

    def run_eagerly(self, timer: PhaseTimer) -> None:
        for _ in range(self.storage.horizon):
            self.step(timer)
            if self.beside is not None:
                self.beside()
        self.finish(timer)

    def step(self, timer: PhaseTimer) -> None:
        """One env step into the storage at the device-held step index, which it advances: the same
        launches at every step, so one captured step replays as any of them."""
        s, t, raw = self.storage, self.step_index, self.last_raw_obs
        s.raw_obs.index_copy_(0, t, raw[None])
        obs = self.normalize(raw)
        critic = None
        if s.critic_obs is not None:
            s.raw_critic_obs.index_copy_(0, t, self.last_raw_critic[None])
            critic = self.normalize_critic(self.last_raw_critic)
            s.critic_obs.index_copy_(0, t, critic[None])
        actions, log_prob, value, mean = self.policy.act(obs, critic)
        timer.lap("collect: policy inference")
        next_obs, reward, terminated, truncated, info = self.env.step(actions)
        timer.lap("collect: env step (physics + task kernels)")
        done = terminated | truncated
        # bootstrapped: an episode cut by the time limit, not one that also ended on its own at that step
        timed_out = truncated & ~terminated
        for buffer, value_t in ((s.obs, obs), (s.actions, actions), (s.log_probs, log_prob), (s.values, value),
                                (s.means, mean), (s.rewards, reward), (s.dones, done), (s.truncated, timed_out),
                                (s.final_obs, info["final_obs"])):
            buffer.index_copy_(0, t, value_t.to(buffer.dtype)[None])
        self.episodes.record(t, reward, done, info)
        if s.critic_obs is not None:
            s.final_critic_obs.index_copy_(0, t, info["final_critic_obs"][None])
            self.last_raw_critic.copy_(info["critic_obs"])
        raw.copy_(next_obs)  # last: with normalize_obs off, obs is this very buffer
        t += 1
        timer.lap("collect: storage and statistics")

    def finish(self, timer: PhaseTimer) -> None:
        """Truncated episodes bootstrapped from their final observation's value, in one batched pass; GAE."""
        cfg, s = self.cfg, self.storage
        if s.critic_obs is None:
            last_values = self.policy.value(self.normalize(self.last_raw_obs))
            final_values = self.policy.value(self.normalize(s.final_obs.flatten(0, 1))).view_as(s.rewards)
        else:
            last_values = self.policy.value(self.normalize_critic(self.last_raw_critic))
            final_values = self.policy.value(self.normalize_critic(s.final_critic_obs.flatten(0, 1))).view_as(s.rewards)
        rewards = s.rewards * cfg.reward_scale + cfg.gamma * final_values * s.truncated
        adv, ret = compute_gae(rewards, s.values, s.dones, last_values, cfg.gamma, cfg.lambda_gae)
        s.advantages.copy_(adv)
        s.returns.copy_(ret)
        # once per rollout, over its whole buffer: cheaper than a check per step
        self.nonfinite += (~torch.isfinite(s.raw_obs)).sum() + (~torch.isfinite(s.rewards)).sum()
        if s.critic_obs is not None:
            self.nonfinite += (~torch.isfinite(s.raw_critic_obs)).sum()
        self.episodes.end_rollout(s.dones)
        self.step_index.zero_()
        timer.lap("bootstrap, GAE")
