"""Scalar logs: JSON lines and CSV always, TensorBoard when it is installed."""

from __future__ import annotations

import csv
import json
import os

COLUMNS = [
    "iteration", "samples", "time_s", "samples_per_s", "iteration_s", "episodes",
    "return", "length", "speed", "eval/return", "eval/length", "eval/speed", "eval_s",
    "loss/surrogate", "loss/value", "loss/entropy", "loss/bounds", "policy/kl", "policy/lr", "policy/noise_std",
]


class MetricsLogger:
    def __init__(self, run_dir: str):
        os.makedirs(run_dir, exist_ok=True)
        self.jsonl_path = os.path.join(run_dir, "metrics.jsonl")
        self.csv_path = os.path.join(run_dir, "metrics.csv")
        new_csv = not os.path.exists(self.csv_path)
        self._csv_file = open(self.csv_path, "a", newline="")
        self._csv = csv.DictWriter(self._csv_file, fieldnames=COLUMNS, extrasaction="ignore")
        if new_csv:
            self._csv.writeheader()
        self._jsonl = open(self.jsonl_path, "a")
        try:
            from torch.utils.tensorboard import SummaryWriter  # noqa: PLC0415

            self._tb = SummaryWriter(os.path.join(run_dir, "tensorboard"))
        except ImportError:
            self._tb = None

    def log(self, row: dict) -> None:
        self._jsonl.write(json.dumps(row) + "\n")
        self._jsonl.flush()
        self._csv.writerow(row)
        self._csv_file.flush()
        if self._tb is not None:
            step = row["samples"]
            for key, value in row.items():
                if key not in ("iteration", "samples") and isinstance(value, (int, float)):
                    self._tb.add_scalar(key, value, step)

    def close(self) -> None:
        self._jsonl.close()
        self._csv_file.close()
        if self._tb is not None:
            self._tb.close()


def read_metrics(run_dir: str) -> list[dict]:
    path = os.path.join(run_dir, "metrics.jsonl")
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no metrics.jsonl in {run_dir}: pass a run directory written by scripts/train.py")
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]
