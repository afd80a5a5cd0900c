"""The loop every learner of agents runs: iterations until a budget (iterations, samples, seconds) or a stop, each
iteration's statistics staged to the host and logged one iteration late (the GPU never waits on logging), the
evaluations, the targets, the checkpoints kept at marks and the atomic saves. A learner (``OnPolicyRunner``,
``agents.sac.OffPolicyRunner``) subclasses ``TrainingLoop``, calls ``init_loop`` and supplies ``iterate()`` (one
iteration: its statistics as device tensors), ``state_dict()``, ``policy`` (``act_deterministic``) and the
normalisers ``normalizer`` and ``critic_normalizer``; ``before_iteration`` and ``close`` are optional."""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass

import torch

from agents.checkpoint import load_bytes, read_checkpoint_bytes, rng_state, save_atomic, set_rng_state
from agents.clock import IterationClock, Lap
from agents.distributed import Workers
from agents.evaluate import evaluate
from agents.logger import MetricsLogger
from agents.profiling import PhaseTimer
from agents.protocol import env_spec


class TrainingLoop:
    UPDATE_PHASE = "update"  # the profile's name for the learner's part of an iteration
    # the learner's own fault counter's help line (agents.protocol's faults), when it keeps one
    NONFINITE_HELP = "the env returned NaN/inf observations or rewards; the learner trained on them"

    def init_loop(self, env, cfg, run_dir: str | None, eval_env, start_time: float | None, print_fn, profile: bool,
                  eval_recorder=None) -> None:
        """The loop's state: counters, logger, clock, faults, curriculum, targets; ``cfg`` has the run fields
        (seed, eval_gap, save_gap, save_at, target, keep_checkpoints)."""
        self.env, self.cfg = env, cfg
        self.spec = env_spec(env)
        self.device = self.spec.device
        self.workers = Workers()
        self.target = cfg.target_pair()
        self.target_reached: dict | None = None  # the first row that reached the config's target
        main = self.workers.is_main
        self.run_dir = run_dir if main else None
        self.logger = MetricsLogger(run_dir) if run_dir and main else None
        self.print = print_fn if main else (lambda s: None)
        self.eval_env = eval_env if main else None
        self.eval_recorder = eval_recorder if main else None
        self.background = None  # an evaluation beside training (agents.background_eval), where the learner has one
        self.start_time = start_time if start_time is not None else time.time()
        self.iteration = 0
        self.samples = 0
        self.elapsed_before = 0.0  # wall-clock seconds of earlier processes of this run (resume)
        self.last_eval_time = 0.0  # set when learn() starts: the first evaluation waits eval_gap
        self.history: list[dict] = []
        self.kept: list[dict] = []  # the checkpoints kept at cfg.save_at: mark, iteration, time (resumes included)
        self.resumes: list[dict] = []  # where each later process of this run took over: iteration, seconds
        self._marks_after = -1.0  # save_at marks up to this many seconds are done (by an earlier process)
        self.timer = PhaseTimer(self.device, enabled=profile)  # --profile: synchronising, per step
        self.clock = IterationClock(self.device)  # always on: events, read one iteration late
        self._stop_request = torch.zeros(1, dtype=torch.float64, device=self.device)
        # running totals of things that should never happen (agents.protocol), logged every row
        self._faults = env.fault_counters() if hasattr(env, "fault_counters") else {}
        self._fault_help = dict(getattr(env, "FAULT_HELP", {}))
        # the env's curriculum state (agents.protocol), a mean over its envs, logged every row as curriculum/<name>
        self._curriculum = env.curriculum if callable(getattr(env, "curriculum", None)) else dict
        self._curriculum_names = list(self._curriculum())
        self._faults_reported: set[str] = set()
        self._stop_requested = False
        self._in_flight: StagedRow | None = None  # an iteration's row on its way to the host (log())
        self._logged_through = 0  # the last iteration whose row is logged: only such a state is saved on an error

    def count_nonfinite(self, counter: torch.Tensor) -> None:
        """Log the learner's own count of non-finite observations or rewards with the env's faults."""
        self._faults = {**self._faults, "nonfinite_obs_rewards": counter}
        self._fault_help["nonfinite_obs_rewards"] = self.NONFINITE_HELP

    # the observation normalisers: a learner sets ``normalizer`` and ``critic_normalizer`` (None where the critic
    # reads the policy's observation)
    def normalize(self, obs: torch.Tensor) -> torch.Tensor:
        return self.normalizer(obs) if self.cfg.normalize_obs else obs

    def normalize_critic(self, critic_obs: torch.Tensor) -> torch.Tensor:
        return self.critic_normalizer(critic_obs) if self.cfg.normalize_obs else critic_obs

    def normalizer_states(self) -> dict:
        return {"normalizer": self.normalizer.state_dict(),
                **({"critic_normalizer": self.critic_normalizer.state_dict()} if self.critic_normalizer is not None
                   else {})}

    def load_normalizers(self, ckpt: dict) -> None:
        self.normalizer.load_state_dict(ckpt["normalizer"])
        if self.critic_normalizer is not None:
            self.critic_normalizer.load_state_dict(ckpt["critic_normalizer"])

    def before_iteration(self, progress: float) -> None:
        """Called before each iteration with how far through its budget the run is, in [0, 1]."""

    def iterate(self) -> dict:
        raise NotImplementedError

    def state_dict(self) -> dict:
        raise NotImplementedError

    def close(self) -> None:
        if self.eval_recorder is not None:
            self.eval_recorder.close()
        if self.device.type == "cuda":
            torch.cuda.synchronize(self.device)

    def loop_state(self) -> dict:
        """The loop's part of a checkpoint: counters, clock, random state, marks kept and resumes."""
        return {"iteration": self.iteration, "samples": self.samples, "elapsed_s": self.elapsed(),
                "rng": rng_state(self.device), "config": self.cfg.to_dict(),
                # a resumed run's summary speaks of the whole run: the marks kept and the resumes before this one
                "kept": list(self.kept), "resumes": list(self.resumes),
                "spec": {"num_obs": self.spec.num_obs, "num_actions": self.spec.num_actions,
                         "num_critic_obs": self.spec.num_critic_obs}}

    def read_checkpoint(self, path: str) -> dict:
        """A checkpoint that rank 0 can read (other processes, on other machines, get its bytes), checked to fit
        this env's observation and action sizes."""
        data = read_checkpoint_bytes(path) if self.workers.is_main else None
        ckpt = load_bytes(self.workers.broadcast_bytes(data, self.device), path, self.device)
        want = (self.spec.num_obs, self.spec.num_actions, self.spec.num_critic_obs)
        have = (ckpt["spec"]["num_obs"], ckpt["spec"]["num_actions"], ckpt["spec"].get("num_critic_obs", 0))
        if want != have:
            raise ValueError(f"checkpoint {path} is for obs/action/critic-obs sizes {have}, this env has {want}: "
                             "pick its task")
        return ckpt

    def resume_loop(self, ckpt: dict) -> None:
        """Go on from a checkpoint's loop state; the metrics logged after it are dropped (they will be again)."""
        self.iteration, self.samples = ckpt["iteration"], ckpt["samples"]
        self.elapsed_before = ckpt["elapsed_s"]
        self._marks_after = self.elapsed_before
        self.kept = list(ckpt.get("kept", []))  # older checkpoints lack both
        self.resumes = [*ckpt.get("resumes", []), {"iteration": self.iteration, "time_s": round(self.elapsed_before, 3)}]
        self.start_time = time.time()
        set_rng_state(ckpt["rng"], self.device)
        if not self.workers.is_main:
            torch.manual_seed(self.rank_seed(self.iteration))
        if self.logger:
            self.logger.drop_rows_after(self.iteration, self.samples)

    def rank_seed(self, iteration: int) -> int:
        """Each process's torch seed: its own per rank, and new at a resume's iteration so that a resumed worker
        does not replay the noise it drew at the start. The multipliers are primes, so that no rank and
        iteration of one run land on another's seed."""
        return self.cfg.seed + 7919 * self.workers.rank + 104729 * iteration

    def elapsed(self) -> float:
        return self.elapsed_before + time.time() - self.start_time

    # ------------------------------------------------------------------ loop
    def learn(self, max_iterations: int | None = None, total_steps: int | None = None,
              time_limit: float | None = None) -> list[dict]:
        """Train until ``max_iterations``, ``total_steps`` samples or ``time_limit`` seconds since
        the process started. A time limit is read with the statistics, one iteration late, so every
        process stops after the same iteration without a host synchronisation of its own."""
        if max_iterations is None and total_steps is None and time_limit is None:
            raise ValueError("give at least one of max_iterations, total_steps, time_limit, or training never stops")
        self._per_iter = per_iter = self.spec.num_envs * self.horizon * self.workers.size  # all processes
        goal = [max_iterations, None if total_steps is None else math.ceil(total_steps / per_iter)]
        last_iter = min([g for g in goal if g is not None], default=None)
        self.last_eval_time = self.elapsed()
        self.clock.restart()
        self._in_flight = None
        self._logged_through = self.iteration  # a fresh or resumed state: its rows are on disk already
        stop = False
        finished = True  # the state is that of a finished iteration
        try:
            while not stop and self._budget_left(last_iter):
                finished = False
                self.clock.mark("idle")  # the GPU waited this long for the host to queue the iteration
                self.before_iteration(self._progress(last_iter, time_limit))
                stats = self.iterate()
                self.clock.mark("update")
                if self.background is not None:  # the evaluation under way: its graph captured, or its steps
                    # queued here where the rollout launched none beside its own (one captured whole); woven
                    # steps are the collect phase's
                    self.background.advance()
                    self.clock.mark("evaluation")
                self.timer.lap(self.UPDATE_PHASE)
                self.iteration += 1
                self.timer.iterations += 1
                self.samples += per_iter
                finished = True
                stop = self.log(stats, last_iter, wants_stop=self._stop_requested or self.target_reached is not None
                                or (time_limit is not None and self.elapsed() >= time_limit))
                self.timer.lap("logging, evaluation, host read")
                if self.iteration % self.cfg.save_gap == 0:
                    # The checkpoint's own row reaches disk first. Every process flushes here, not only
                    # rank 0, which saves: a flush reads the stop request of the row it logs, and a
                    # process that read it one iteration before the others would leave them waiting in
                    # the next iteration's collectives forever (a finished job that never exits). Read before
                    # it is written, that row tells whether it is the run's last: a stop read by now or with
                    # it, or the budget spent. The last carries the final evaluation.
                    arrived = self._arrive()
                    if arrived is not None:
                        stop = stop or arrived.stop
                        self._log_row(arrived, last_iter, final=stop or not self._budget_left(last_iter))
                    if self.run_dir:
                        self.save()
                self._keep_if_due()
            self.flush_log(last_iter, final=True)  # the last iteration always carries an evaluation
        finally:
            # Interrupted: keep the finished iteration's row if it can be read, and save only a
            # finished iteration whose row is on disk. An error inside an iteration may leave the
            # policy half updated; an iteration whose statistics could not be gathered (a peer died
            # in that collective) has no row, and a resume from it would never log one (it keeps the
            # rows up to its checkpoint). Either way the last checkpoint stands: at most save_gap
            # iterations are lost, and the metrics have no gap.
            try:
                self.flush_log(last_iter, may_evaluate=False)
            except Exception:  # noqa: BLE001  (the original error is the one to see)
                pass
            if self.run_dir and finished and self._logged_through == self.iteration:
                self.save()
        return self.history

    def _budget_left(self, last_iter: int | None) -> bool:
        """Whether the iteration budget (from the iteration or sample goal) allows another iteration."""
        return last_iter is None or self.iteration < last_iter

    def _progress(self, last_iter: int | None, time_limit: float | None) -> float:
        """How far through its budget the run is, in [0, 1]: the furthest of its iterations (from the
        iteration or sample goal) and its time limit, both counted from the run's start, resumes included."""
        done = [self.iteration / last_iter if last_iter else 0.0,
                self.elapsed() / time_limit if time_limit else 0.0]
        return min(max(done), 1.0)

    def log(self, stats: dict, last_iter: int | None, wants_stop: bool) -> bool:
        """Queue this iteration's row to the host and log the previous one, which arrived long ago:
        logging never makes the GPU wait. Returns whether any process asked to stop."""
        staged = self._stage_row(stats, wants_stop)
        stop = self.flush_log(last_iter)
        self._in_flight = staged
        return stop

    def flush_log(self, last_iter: int | None, final: bool = False, may_evaluate: bool = True) -> bool:
        """Log the row in flight now, if there is one (one host wait); return whether any process asked to
        stop with it. ``final``: the run's last row, which always carries an evaluation."""
        arrived = self._arrive()
        if arrived is None:
            return False
        self._log_row(arrived, last_iter, final, may_evaluate)
        return arrived.stop

    def _arrive(self) -> ArrivedRow | None:
        """The row in flight, read on the host (the one wait for it), and no longer in flight."""
        staged, self._in_flight = self._in_flight, None
        return None if staged is None else ArrivedRow(staged, staged.host.tolist())

    def request_stop(self) -> None:
        """Stop after the iteration in flight and save (safe to call from a signal handler). Under
        several processes the request travels with the statistics, so all stop at one iteration."""
        self._stop_requested = True

    @property
    def stop_requested(self) -> bool:
        return self._stop_requested

    def _stage_row(self, stats: dict, wants_stop: bool) -> StagedRow:
        """Queue the copy of an iteration's statistics to the host, without waiting for it. The
        episode sums and the stop request travel in one collective, summed over the processes."""
        self._stop_request.fill_(1.0 if wants_stop else 0.0)
        faults = [t.reshape(1).to(torch.float64) for t in self._faults.values()]
        # each process's means weighted by its envs (several GPUs may hold different numbers), and the weight
        weight = float(self.spec.num_envs)
        curriculum = [torch.as_tensor(v, device=self.device).reshape(1).to(torch.float64) * weight
                      for v in self._curriculum().values()]
        counts = [torch.full((1,), weight, dtype=torch.float64, device=self.device)] if curriculum else []
        shared = self.workers.sum_(torch.cat([self.episodes.take(), *faults, *curriculum, *counts,
                                              self._stop_request]))
        keys = list(stats)
        values = torch.cat([torch.stack([stats[k].float() for k in keys]).double(), shared])
        self.clock.mark("statistics")
        pinned = self.device.type == "cuda"
        host = torch.empty(values.shape, dtype=values.dtype, pin_memory=pinned)
        host.copy_(values, non_blocking=pinned)
        return StagedRow(self.iteration, self.samples, keys, host, self.clock.finish())

    def _log_row(self, arrived: ArrivedRow, last_iter: int | None, final: bool = False,
                 may_evaluate: bool = True) -> None:
        """Log a row read on the host, evaluating first when one is due (always when ``final``)."""
        staged, values = arrived.staged, arrived.values
        seconds = self.clock.seconds(staged.lap)
        keys = staged.keys
        row = {"iteration": staged.iteration, "samples": staged.samples, "time_s": round(self.elapsed(), 3),
               "samples_per_s": self._per_iter / max(seconds["iteration"], 1e-9), "iteration_s": seconds["iteration"]}
        row.update({f"phase/{k}_s": v for k, v in seconds.items() if k != "iteration"})
        if self.device.type == "cuda":  # allocator counters: host-side, no synchronisation
            row["memory/allocated_mib"] = torch.cuda.memory_allocated(self.device) / 2**20
            row["memory/reserved_mib"] = torch.cuda.memory_reserved(self.device) / 2**20
        row.update(dict(zip(keys, values[: len(keys)])))
        episode_end = len(keys) + self.episodes.size
        row.update(self.episodes.summary(values[len(keys) : episode_end]))
        fault_end = episode_end + len(self._faults)
        if self._curriculum_names:
            envs = values[-2]
            row.update({f"curriculum/{name}": v / envs
                        for name, v in zip(self._curriculum_names, values[fault_end:-2])})
        for name, count in zip(self._faults, values[episode_end:fault_end]):
            row[f"faults/{name}"] = int(count)
            if count > 0 and name not in self._faults_reported:  # once per run: not a line per step
                self._faults_reported.add(name)
                self.print(f"warning: {name} = {int(count)} by iteration {staged.iteration} (all processes): "
                           f"{self._fault_help.get(name, 'see the env documentation')}")
        due = final or self.elapsed() - self.last_eval_time >= self.cfg.eval_gap
        if self.background is not None and may_evaluate and not final:
            row.update(self.background.poll() or {})
            if due and not self.background.running:
                self.last_eval_time = self.elapsed()
                self.background.start(self.policy, self.normalizer, {
                    "time_s": round(self.last_eval_time, 3), "samples": self.samples, "iteration": self.iteration})
        elif self.eval_env is not None and may_evaluate and due:
            if self.background is not None:  # the last evaluation: one of its own, now
                self.background.drop()
            t_eval = time.perf_counter()
            row.update(self.evaluate())
            if self.eval_recorder is not None:
                self.eval_recorder.finish(staged.iteration, staged.samples)
            row["eval_s"] = time.perf_counter() - t_eval
            row["time_s"] = round(self.elapsed(), 3)
            self.clock.restart()  # the iteration queued before the evaluation is timed without it
        self.history.append(row)
        value = row.get(self.target[0]) if self.target else None
        if value is not None and self.target_reached is None and value >= self.target[1]:
            # rank 0 alone evaluates: its stop travels with the next iteration's statistics to every process
            self.target_reached = {k: row[k] for k in ("iteration", "samples", "time_s", self.target[0])}
            self.print(f"target {self.target[0]} >= {self.target[1]:g} reached at iteration {row['iteration']} "
                       f"({row[self.target[0]]:.4g} at {row['time_s']:.1f} s): stopping")
        if self.logger:
            self.logger.log(row)
        self._logged_through = staged.iteration
        self.print(progress_line(row, last_iter))

    def evaluate(self) -> dict:
        self.last_eval_time = self.elapsed()
        spec = env_spec(self.eval_env)
        return evaluate(self.eval_env, self.policy, self.normalize, spec.max_episode_steps, self.eval_recorder)

    def save(self, path: str | None = None) -> str:
        state = self.state_dict()
        if path is None and self.cfg.keep_checkpoints:  # rsl_rl's model_<it>.pt: policies to compare later
            save_atomic(state, os.path.join(self.run_dir, f"checkpoint-{self.iteration}.pt"))
        path = path or os.path.join(self.run_dir, "checkpoint.pt")
        save_atomic(state, path)
        return path

    def _keep_if_due(self) -> None:
        """Keep checkpoint-<iteration>.pt once a ``save_at`` mark has passed (rank 0; a copy for later
        comparison, not the file a resume reads, so its row need not be on disk first)."""
        marks = [t for t in self.cfg.save_at if t > self._marks_after]
        now = self.elapsed()
        if not (self.run_dir and marks and now >= marks[0]):
            return
        passed = [t for t in marks if t <= now]
        self._marks_after = passed[-1]
        path = os.path.join(self.run_dir, f"checkpoint-{self.iteration}.pt")
        save_atomic(self.state_dict(), path)
        self.kept.append({"mark_s": passed[-1], "marks_s": passed, "iteration": self.iteration,
                          "samples": self.samples, "time_s": round(now, 3), "path": path})


@dataclass
class StagedRow:
    """An iteration's statistics on their way to pinned host memory, and its clock marks."""

    iteration: int
    samples: int
    keys: list[str]
    host: torch.Tensor
    lap: Lap


@dataclass
class ArrivedRow:
    """A staged row read on the host; the stop request summed over the processes is its last value."""

    staged: StagedRow
    values: list[float]

    @property
    def stop(self) -> bool:
        return self.values[-1] > 0


def progress_line(row: dict, last_iter: int | None) -> str:
    it = row["iteration"]
    if last_iter:
        frac = min(it / last_iter, 1.0)
        bar = "#" * int(20 * frac) + "." * (20 - int(20 * frac))
        head = f"it {it:5d}/{last_iter} [{bar}] {100 * frac:5.1f}%"
    else:
        head = f"it {it:5d}"

    def fmt(key, spec, unit=""):
        v = row.get(key)
        return "  -  " if v is None else f"{v:{spec}}{unit}"

    m, s = divmod(int(row["time_s"]), 60)
    # the env's curriculum state (a rough task's mean terrain level), where it has one
    curriculum = "".join(f" | {k.split('/', 1)[1].replace('_', ' ')} {v:.2f}" for k, v in row.items()
                         if k.startswith("curriculum/"))
    line = (f"{head} | {row['samples'] / 1e6:8.2f}M samples | {row['samples_per_s'] / 1e3:7.1f}k/s | "
            f"return {fmt('return', '8.1f')} | speed {fmt('speed', '5.2f', ' m/s')}{curriculum} | {m:02d}:{s:02d}")
    if "eval/return" in row:
        line += f" | eval {row['eval/return']:.1f} @ {row['eval/speed']:.2f} m/s"
    return line
