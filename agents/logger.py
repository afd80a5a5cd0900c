"""Scalar logs: JSON lines and CSV always, TensorBoard when it is installed.

Each row is appended and flushed whole, so a run killed at any moment leaves at most one torn
last line, which ``read_metrics`` skips and a resume removes."""

from __future__ import annotations

import csv
import io
import json
import os
import statistics

COLUMNS = [
    "iteration", "samples", "time_s", "samples_per_s", "iteration_s", "episodes",
    "return", "length", "speed", "eval/return", "eval/length", "eval/speed", "eval_s",
    "loss/surrogate", "loss/value", "loss/entropy", "loss/bounds", "policy/kl", "policy/lr", "policy/noise_std",
    "policy/lr_mean", "policy/lr_max", "policy/kl_max",
    "phase/idle_s", "phase/collect_s", "phase/normalizer_s", "phase/update_s", "phase/statistics_s",
    "faults/nan_actions", "faults/diverged_resets", "faults/solver_overflows", "faults/nonfinite_obs_rewards",
    "memory/allocated_mib", "memory/reserved_mib",
]


class MetricsLogger:
    def __init__(self, run_dir: str):
        os.makedirs(run_dir, exist_ok=True)
        self.run_dir = run_dir
        self.jsonl_path = os.path.join(run_dir, "metrics.jsonl")
        self.csv_path = os.path.join(run_dir, "metrics.csv")
        self._purge_step: int | None = None
        self._tb = None
        self._tb_tried = False
        self._open()

    def _open(self) -> None:
        new_csv = not os.path.exists(self.csv_path)
        self._csv_file = open(self.csv_path, "a", newline="")
        self._csv = csv.DictWriter(self._csv_file, fieldnames=COLUMNS, extrasaction="ignore")
        if new_csv:
            self._csv.writeheader()
            self._csv_file.flush()
        self._jsonl = open(self.jsonl_path, "a")

    def _tensorboard(self):
        if not self._tb_tried:
            self._tb_tried = True
            try:
                from torch.utils.tensorboard import SummaryWriter  # noqa: PLC0415

                self._tb = SummaryWriter(os.path.join(self.run_dir, "tensorboard"), purge_step=self._purge_step)
            except ImportError:
                self._tb = None
        return self._tb

    def log(self, row: dict) -> None:
        self._jsonl.write(json.dumps(row) + "\n")
        self._jsonl.flush()
        self._csv.writerow(row)
        self._csv_file.flush()
        tb = self._tensorboard()
        if tb is not None:
            step = row["samples"]
            for key, value in row.items():
                if key not in ("iteration", "samples") and isinstance(value, (int, float)):
                    tb.add_scalar(key, value, step)

    def drop_rows_after(self, iteration: int, samples: int) -> int:
        """Keep the rows up to ``iteration`` (a resumed run's checkpoint) and drop the rest, which
        the resumed run logs again, and any torn line; TensorBoard drops steps past ``samples``.
        Both files are rewritten atomically. Returns how many rows were dropped."""
        self.close()
        rows = read_metrics(self.run_dir) if os.path.exists(self.jsonl_path) else []
        kept = [r for r in rows if r.get("iteration", 0) <= iteration]
        _rewrite(self.jsonl_path, "".join(json.dumps(r) + "\n" for r in kept))
        buf = io.StringIO()
        writer = csv.DictWriter(buf, fieldnames=COLUMNS, extrasaction="ignore")
        writer.writeheader()
        writer.writerows(kept)
        _rewrite(self.csv_path, buf.getvalue())
        self._purge_step = samples + 1
        self._tb, self._tb_tried = None, False
        self._open()
        return len(rows) - len(kept)

    def close(self) -> None:
        self._jsonl.close()
        self._csv_file.close()
        if self._tb is not None:
            self._tb.close()


def _rewrite(path: str, text: str) -> None:
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "w", newline="") as f:
        f.write(text)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def read_metrics(run_dir: str) -> list[dict]:
    """The rows of a run; a torn last line (the process was killed mid-write) is skipped."""
    path = os.path.join(run_dir, "metrics.jsonl")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no metrics.jsonl in {run_dir}: pass a run directory written by warpgym train")
    rows = []
    with open(path) as f:
        lines = f.read().split("\n")
    for i, line in enumerate(lines):
        if not line.strip():
            continue
        try:
            rows.append(json.loads(line))
        except json.JSONDecodeError:
            if i < len(lines) - 1 and any(rest.strip() for rest in lines[i + 1 :]):
                raise ValueError(f"{path} line {i + 1} is not JSON and not the last line: the file is "
                                 "damaged") from None
    return rows


def steady_median(rows: list[dict], key: str = "samples_per_s") -> float | None:
    """The median of ``key`` once a run has settled: its first fifth (compiles, graph captures,
    warm-up) left out. Every throughput this project reports is this."""
    values = [r[key] for r in rows[len(rows) // 5 :] if r.get(key) is not None]
    return statistics.median(values) if values else None


def first_reaching(rows: list[dict], key: str, value: float) -> dict | None:
    """When (``time_s``, ``samples``) the logged ``key`` first reached ``value``, or None."""
    hit = next((r for r in rows if r.get(key) is not None and r[key] >= value), None)
    return None if hit is None else {"time_s": hit["time_s"], "samples": hit["samples"]}


def learning_clock(rows: list[dict]) -> list[float]:
    """Each row's learning time: seconds since the first row up to the moment the row was logged (or its
    evaluation began), with the evaluations logged before it left out, so that how often a run evaluates
    does not move it (on several GPUs the others wait for rank 0's evaluation, so it is left out of theirs too)."""
    out, evaluating = [], 0.0
    start = rows[0]["time_s"] - rows[0].get("eval_s", 0.0) if rows else 0.0
    for r in rows:
        out.append(round(r["time_s"] - r.get("eval_s", 0.0) - start - evaluating, 3))
        evaluating += r.get("eval_s", 0.0)
    return out


def first_window(rows: list[dict], key: str, value: float, smooth: int = 1) -> list[int] | None:
    """The indices of the first ``smooth`` consecutive rows holding ``key`` (rows without it skipped) whose mean of
    ``key`` reaches ``value``, the reaching row last; None if no window does. A training return is the mean of the
    episodes that ended in one iteration, noisier than an evaluation's: a window keeps one lucky row from counting."""
    if not isinstance(smooth, int) or smooth < 1:
        raise ValueError(f"smooth={smooth!r}: the number of logged values averaged, 1 or more")
    have = [i for i, r in enumerate(rows) if r.get(key) is not None]
    for j in range(smooth - 1, len(have)):
        window = have[j - smooth + 1:j + 1]
        if sum(rows[i][key] for i in window) / smooth >= value:
            return window
    return None


def time_to_target(rows: list[dict], key: str, value: float, smooth: int = 1) -> dict | None:
    """When a run's logged ``key`` (``eval/return``, ``eval/speed``, ``speed``, ...), averaged over ``smooth`` rows
    (``first_window``), first reached ``value``, or None; ``key`` holds that mean.

    ``time_s``: seconds since the process started, up to the moment that row's evaluation began (wall-clock,
    everything counted); ``learning_s``: its ``learning_clock``; the run's start-up is ``time_s - learning_s``."""
    window = first_window(rows, key, value, smooth)
    if window is None:
        return None
    hit = window[-1]
    row = rows[hit]
    return {"time_s": round(row["time_s"] - row.get("eval_s", 0.0), 3), "learning_s": learning_clock(rows[:hit + 1])[-1],
            "samples": row["samples"], "iteration": row["iteration"], key: sum(rows[i][key] for i in window) / smooth}
