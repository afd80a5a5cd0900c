"""Worker parallelism: two processes (torchrun, gloo on the CPU) train one policy."""

import os
import subprocess
import sys

import torch

from agents.logger import read_metrics

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def torchrun(*args, timeout=300):
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node=2", *args]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=timeout, env=env)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done


def test_two_processes_keep_one_policy_and_share_statistics(tmp_path):
    torchrun("tests/dist_worker.py", str(tmp_path), "5")
    a, b = (torch.load(tmp_path / f"rank{r}.pt", weights_only=False) for r in (0, 1))
    assert not torch.equal(a["first_obs"], b["first_obs"])  # each process has its own envs
    torch.testing.assert_close(a["params"], b["params"], atol=1e-6, rtol=0)  # yet one policy
    torch.testing.assert_close(a["mean"], b["mean"])
    assert a["count"].item() == b["count"].item() == 2 * 32 * (1 + 5 * 10)  # both processes' samples
    assert a["lr"].item() == b["lr"].item()
    # rank 0 logs the samples of both processes, and only rank 0 writes: one row per iteration
    assert [r["samples"] for r in a["history"]] == [2 * 32 * 10 * i for i in range(1, 6)]
    assert len(read_metrics(str(tmp_path / "run"))) == 5


def test_train_script_under_torchrun_on_the_cpu(tmp_path):
    run = tmp_path / "ant"
    done = torchrun("scripts/train.py", "--task", "Ant", "--device", "cpu", "--num-envs", "4",
                    "--max-iterations", "2", "--horizon-len", "4", "--episode-length", "20",
                    "--no-eval", "--no-plots", "--run-dir", str(run))
    assert "x 2 processes" in done.stdout
    summary = (run / "summary.json").read_text()
    assert '"iterations": 2' in summary
    rows = (run / "metrics.jsonl").read_text().splitlines()
    assert len(rows) == 2 and '"samples": 64' in rows[1]  # 2 processes x 4 envs x 4 steps x 2 iterations
