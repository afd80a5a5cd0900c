"""Evaluation beside training (``Config.eval_background``).

An evaluation plays one episode per eval env, up to the episode length (1000 steps for most of Gymnasium's
tasks), one step after another. On a GPU each step of 64 worlds is bound by the simulator's kernel launches,
not by work, so a synchronous evaluation every 60 s costs 8-16 % of a 10-minute run (docs/benchmarks.md,
"Presets") and says only every minute how far the policy has come.

Here an evaluation plays a frozen copy of the policy and of the observation normaliser (taken when it starts), one
step beside each of the training rollout's: the collector calls ``beside()`` after each of its steps, and each call
replays the evaluation's step, captured once as a one-step CUDA graph, on a side stream of its own, for its small
kernels to run beside the training's. Its result goes to pinned host memory on that stream and is read once an event
says it is there: neither stream waits for the other during the evaluation. One step at a time because a replay
holds the host: on an H200 the launch of a 32-step graph of MuJoCo Warp steps returned only once most of it had run
(145-151 ms of its 158-164), so a chunk queued after the iteration mostly took turns with the next one (0.24-0.29 of
it overlapped), while a graph of one env step returns in 0.2-0.5 ms and the steps woven one by one overlapped 0.85-0.88
(benchmarks/speed/background_overlap.py; docs/history.md, "Walker2d-v5's evaluations"). Where the rollout has no
steps to weave into (captured whole), ``advance()`` queues ``STEPS_PER_ITERATION`` steps after the iteration. Its
row is the one logged when the result is read, so the minutes it gives to a target are those at which the number
was known; ``eval/policy_time_s`` says when its policy was taken.

On the CPU (or where the capture fails, or an env cannot be captured) the same steps run eagerly, woven into the
rollout's likewise: the numbers are those a synchronous evaluation of the same weights gives (tests/test_agents.py).
"""

from __future__ import annotations

import copy

import torch

from agents.collect import WholeRollout, capture_rollout
from agents.evaluate import EpisodeTally

# eval steps queued per iteration by advance() where the rollout wove none in: 32 steps of 64 worlds took 0.17-0.28 s
# as synchronous evaluations (a 1000-step evaluation: Walker2d-v5's 5.4 s on an H200, Ant-v5's 8.7 s on an H100),
# beside iterations of 4096 worlds x 32 steps of 0.13-0.69 s; an evaluation of 1000 steps spans 32 iterations, as
# it does woven into the presets' 32-step rollouts
STEPS_PER_ITERATION = 32


class BackgroundEvaluation:
    """One evaluation at a time of ``env``: a step per ``beside()`` (the collector's, after each rollout step), or
    ``STEPS_PER_ITERATION`` per ``advance()`` where the iteration's rollout launched none."""

    def __init__(self, env, policy, normalizer, normalize_obs: bool, max_steps: int, device: torch.device,
                 capturable: bool, print_fn=print):
        self.env, self.normalize_obs, self.device, self.print = env, normalize_obs, device, print_fn
        self.policy = copy.deepcopy(policy).requires_grad_(False)  # the frozen copy it plays (graph reads by address)
        self.normalizer = copy.deepcopy(normalizer)
        self.tally = EpisodeTally(env.num_envs, max_steps, device)
        self.max_steps = max_steps
        cuda = device.type == "cuda"
        self.stream = torch.cuda.Stream(device) if cuda else None
        self.capture = cuda and capturable
        self.graph: WholeRollout | None = None  # one step's graph, once captured
        self.obs: torch.Tensor | None = None  # the env's latest observation, in a buffer of this object's own
        self.host = None  # the result's pinned host copy
        self.done: torch.cuda.Event | None = None
        self.left = 0  # steps still to queue
        self.stamp: dict | None = None  # when the evaluated policy was taken; None: no evaluation under way
        self._eager_steps = 0
        self._woven = 0  # steps queued by beside() since the last advance()
        self._joined = False  # whether the side stream has waited for the current stream since the last eager work

    @property
    def running(self) -> bool:
        return self.stamp is not None

    @torch.no_grad()
    def start(self, policy, normalizer, stamp: dict) -> None:
        """Begin an evaluation of ``policy`` (and ``normalizer``) as they are now; ``stamp`` (time, samples,
        iteration) comes back with its result."""
        self.policy.load_state_dict(policy.state_dict())  # in place: a captured graph reads these tensors
        self.normalizer.load_state_dict(normalizer.state_dict())
        obs, _ = self.env.reset()
        if self.obs is None:
            self.obs = obs.clone()
        else:
            self.obs.copy_(obs)
        self.tally.reset()
        self.left, self.stamp, self.done, self._joined = self.max_steps, stamp, None, False

    def play_step(self) -> None:
        """One step of every eval env by the frozen policy, tallied (what the graph captures)."""
        obs = self.normalizer(self.obs) if self.normalize_obs else self.obs
        next_obs, reward, terminated, truncated, info = self.env.step(self.policy.act_deterministic(obs))
        self.tally.add(reward, terminated, truncated, info)
        self.obs.copy_(next_obs)

    def beside(self) -> None:
        """Queue the evaluation's next step, after a step of the training's (none if no evaluation is under way or
        all its steps are queued). Called after every rollout step: nothing but the check when idle."""
        if self.left > 0:
            with torch.no_grad():
                self._queue_step()
            self._woven += 1

    @torch.no_grad()
    def advance(self) -> None:
        """Between iterations: capture the step once its kernels have run eagerly, and queue
        ``STEPS_PER_ITERATION`` steps if the iteration's rollout wove none in."""
        woven, self._woven = self._woven, 0
        if self.capture and self.graph is None and self._eager_steps > 0:
            self.graph = self._capture()
        if woven == 0:
            for _ in range(min(STEPS_PER_ITERATION, self.left)):
                self._queue_step()

    def _queue_step(self) -> None:
        if self.graph is not None:
            if not self._joined:  # the reset, the copied weights and any eager steps come first
                self.stream.wait_stream(torch.cuda.current_stream(self.device))
                self._joined = True
            with torch.cuda.stream(self.stream):
                self.graph.replay()
        else:
            self.play_step()
            self._eager_steps += 1
            self._joined = False
        self.left -= 1
        if self.left == 0:
            self._stage()

    def _capture(self):
        try:  # one step as a graph, as the rollout's step is (nothing runs while capturing)
            return capture_rollout("rollout", self.play_step, lambda: None, 1, self.device)
        except RuntimeError as e:
            # nothing ran during the failed capture: the steps go on eagerly, beside nothing
            self.capture = False
            self.print(f"warning: capturing the background evaluation as a CUDA graph failed ({e}); "
                       "its steps run eagerly, between the training's")
            return None

    def _stage(self) -> None:
        """The result's copy to the host, queued behind the evaluation's last steps."""
        if self.stream is None:
            self.host = self.tally.means()
            return
        if not self._joined:
            self.stream.wait_stream(torch.cuda.current_stream(self.device))
        with torch.cuda.stream(self.stream):
            means = self.tally.means()
            if self.host is None or self.host.shape != means.shape:
                self.host = torch.empty(means.shape, dtype=means.dtype, pin_memory=True)
            self.host.copy_(means, non_blocking=True)
            self.done = torch.cuda.Event()
            self.done.record(self.stream)

    def poll(self) -> dict | None:
        """The finished evaluation's row entries (with its policy's time and samples), once its result is on
        the host; None while it runs or when none is under way. Never waits."""
        if self.stamp is None or self.left > 0 or (self.done is not None and not self.done.query()):
            return None
        row = self.tally.row(self.host.tolist())
        row.update({f"eval/policy_{k}": v for k, v in self.stamp.items()})
        self.stamp = None
        return row

    def drop(self) -> None:
        """Abandon the evaluation under way (the run ends with a synchronous one)."""
        if self.stream is not None:
            torch.cuda.current_stream(self.device).wait_stream(self.stream)  # its env is free again
        self.left, self.stamp = 0, None

    def close(self) -> None:
        self.drop()
        self.graph = None
