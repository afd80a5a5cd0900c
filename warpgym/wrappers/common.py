"""What every learner adapter shares: the warpgym env underneath, and the same episode metrics.

A learner keeps its own statistics in its own format; ``EpisodeLog`` reads warpgym's episode
statistics (``info["episode"]``) at every step into device-side sums and reports them every
``every`` steps, so runs of different learners can be plotted on one figure. Reporting reads the
device once per report, not once per step.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import torch


class TimeLimitReached(Exception):
    """Raised from ``step`` once ``EpisodeLog.stop_after_s`` has passed: the one way to stop any
    learner's loop at a wall-clock limit without touching its code. Catch it around ``learn``."""


class ObsCopies:
    """Observations copied into two device buffers by turns, for learners that keep a reference to
    the observation they acted on until after the next step (which overwrites warpgym's buffer).
    The learner sees each copy live for two steps; nothing is allocated per step."""

    def __init__(self, like: torch.Tensor):
        self.buffers = (torch.empty_like(like), torch.empty_like(like))
        self.index = 1

    def __call__(self, obs: torch.Tensor) -> torch.Tensor:
        self.index ^= 1
        return self.buffers[self.index].copy_(obs)


def base_env(env):
    """The warpgym vector env (``LocomotionVecEnv``, ``SuiteVecEnv``) under a Gymnasium wrapper chain or one of
    these adapters (or the env itself)."""
    inner = getattr(env, "_base", None)
    if inner is None:
        inner = getattr(env, "unwrapped", env)
    if not hasattr(inner, "sim") or not hasattr(inner, "info"):
        raise TypeError(f"{type(env).__name__} is not a warpgym vector env (or a wrapper of one): build it with "
                        "warpgym.envs.make_vec_env or gymnasium.make_vec('warpgym/Ant-v0', ...)")
    return inner


# (row name, info["episode"] key) of the statistics only some tasks report
OPTIONAL_FIELDS = (("speed", "s"), ("error_vel_xy", "error_vel_xy"), ("error_vel_yaw", "error_vel_yaw"))


class EpisodeLog:
    """Device-side sums of the episodes that end at each step, reported every ``every`` steps.

    Args:
        env: the warpgym vector env.
        every: steps between reports (a learner's rollout length is a good choice).
        sink: called with a row ``{"samples", "episodes", "return", "length", "steps_s", ...}``
            (means over the episodes that ended since the last report, with ``speed`` for the tasks
            that walk forward and the tracking errors ``error_vel_xy``, ``error_vel_yaw`` for the
            legged ones; ``steps_s`` the wall-clock seconds since then).
        stop_after_s: raise ``TimeLimitReached`` at the first report this many seconds after
            ``start`` (default: never).
        start: the clock's origin (default: now).
        keep_returns: also list every episode's return in ``returns`` (a host read per step: for checks).
    """

    def __init__(self, env, every: int, sink: Callable[[dict], None] | None = None,
                 stop_after_s: float | None = None, start: float | None = None, keep_returns: bool = False):
        if not isinstance(every, int) or every < 1:
            raise ValueError(f"every={every!r} must be a positive number of steps")
        self.env = base_env(env)
        self.every, self.sink, self.stop_after_s = every, sink, stop_after_s
        self.start = time.time() if start is None else start
        self._last = time.time()
        # the episode statistics this task reports, under the metrics' names
        episode = self.env.info["episode"]
        self._fields = [(row, key) for row, key in OPTIONAL_FIELDS if key in episode]
        self._sums = torch.zeros(3 + len(self._fields), dtype=torch.float64, device=self.env.device)
        self.steps = 0
        self.keep_returns = keep_returns
        self.returns: list[float] = []

    def after_step(self, info: dict) -> None:
        ep = info["episode"]
        done = ep["_r"]
        w = done.float()
        # one (K, N) @ (N,) product: episodes ended, and their summed return, length, speed or errors
        self._sums += torch.stack((w, ep["r"], ep["l"].float(), *(ep[key] for _, key in self._fields))) @ w
        if self.keep_returns:  # every episode's return, in the order they ended (host reads: tests only)
            self.returns.extend(ep["r"][done].tolist())
        self.steps += 1
        if self.steps % self.every == 0:
            self.report()

    def report(self) -> None:
        episodes, ret, length, *more = self._sums.tolist()  # the one host read per report
        self._sums.zero_()
        now = time.time()
        row = {"samples": self.steps * self.env.num_envs, "episodes": int(episodes), "steps_s": now - self._last,
               "time_s": now - self.start}
        if episodes:
            row.update({"return": ret / episodes, "length": length / episodes})
            row.update({name: total / episodes for (name, _), total in zip(self._fields, more)})
        self._last = now
        if self.sink is not None:
            self.sink(row)
        if self.stop_after_s is not None and now - self.start >= self.stop_after_s:
            raise TimeLimitReached(f"{self.stop_after_s:g} s since start")
