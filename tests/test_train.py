"""scripts/train.py end to end on the CPU: a short Ant run writes everything, and a resume continues it."""

import json
import os
import sys

import torch

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))

import play  # noqa: E402
import train  # noqa: E402

from agents.checkpoint import load  # noqa: E402
from agents.logger import read_metrics  # noqa: E402


def test_short_cpu_run_writes_logs_checkpoint_plots_resumes_and_plays(tmp_path, capsys):
    run = str(tmp_path / "ant")
    common = ["--horizon-len", "8", "--save-gap", "2", "--eval-gap", "0", "--eval-envs", "2",
              "--episode-length", "40"]
    assert train.main(["--task", "Ant", "--device", "cpu", "--num-envs", "8", "--max-iterations", "3",
                       "--run-dir", run, *common]) == 0
    for name in ("config.json", "metrics.jsonl", "metrics.csv", "checkpoint.pt", "summary.json",
                 "reward_vs_time.png", "reward_vs_samples.png"):
        assert os.path.getsize(os.path.join(run, name)) > 0, name
    rows = read_metrics(run)
    assert [r["iteration"] for r in rows] == [1, 2, 3]
    assert all(r["samples"] == 64 * r["iteration"] for r in rows)
    assert all("eval/return" in r for r in rows) and rows[-1]["episodes"] >= 0
    assert load(os.path.join(run, "checkpoint.pt"), torch.device("cpu"))["iteration"] == 3
    saved = json.load(open(os.path.join(run, "config.json")))
    assert saved["num_envs"] == 8 and saved["batch_size"] == 32  # 8 envs x 8 steps, two mini-batches

    assert train.main(["--resume", run, "--max-iterations", "5", "--no-plots"]) == 0
    rows = read_metrics(run)
    assert [r["iteration"] for r in rows] == [1, 2, 3, 4, 5]
    assert rows[3]["time_s"] > rows[2]["time_s"]  # the wall-clock axis carries on across processes
    assert load(os.path.join(run, "checkpoint.pt"), torch.device("cpu"))["samples"] == 5 * 64

    # the deterministic policy of that run plays full 40-step episodes and reports return and speed
    assert play.main([run, "--device", "cpu", "--num-envs", "2"]) == 0
    result = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert result["iteration"] == 5 and result["episodes"] == 2
    assert 0 < result["eval/length"] <= 40 and result["eval/return"] != 0
