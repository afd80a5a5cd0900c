"""Worker parallelism on the CPU (gloo): processes of one torchrun job train one policy, on one
machine or on two "machines" (two torchrun agents on localhost), a lost worker stops the job, and
a killed run resumes with another number of processes."""

import json
import os
import signal
import subprocess
import sys
import threading
import time
from datetime import timedelta

import pytest
import torch
import torch.distributed as dist

from agents.checkpoint import load
from agents.distributed import PeerWatch
from agents.logger import read_metrics

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ENV = dict(os.environ, OMP_NUM_THREADS="1")


def torchrun_args(nproc: int = 2):
    return [sys.executable, "-m", "torch.distributed.run", "--standalone", f"--nproc_per_node={nproc}"]


def torchrun(*args, nproc=2, timeout=300):
    done = subprocess.run([*torchrun_args(nproc), *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=timeout, env=ENV)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done


def check_one_policy(out, iterations):
    a, b = (torch.load(out / f"rank{r}.pt", weights_only=False) for r in (0, 1))
    assert not torch.equal(a["first_obs"], b["first_obs"])  # each process has its own envs
    torch.testing.assert_close(a["params"], b["params"], atol=1e-6, rtol=0)  # yet one policy
    torch.testing.assert_close(a["mean"], b["mean"])
    assert a["count"].item() == b["count"].item() == 2 * 32 * (1 + iterations * 10)  # both processes' samples
    assert a["lr"].item() == b["lr"].item()
    # rank 0 logs the samples of both processes, and only rank 0 writes: one row per iteration
    assert [r["samples"] for r in a["history"]] == [2 * 32 * 10 * i for i in range(1, iterations + 1)]
    assert len(read_metrics(str(out / "run"))) == iterations


def test_two_processes_keep_one_policy_and_share_statistics(tmp_path):
    torchrun("tests/dist_worker.py", str(tmp_path), "5")
    check_one_policy(tmp_path, 5)


def test_two_machines_on_localhost_keep_one_policy(tmp_path):
    """Two torchrun agents, one process each, meet through a c10d rendezvous as two nodes would.
    The rendezvous store is held here, on a port the OS picked, so no port can be taken twice."""
    store = dist.TCPStore("127.0.0.1", 0, is_master=True, wait_for_workers=False, timeout=timedelta(seconds=60))
    nodes = []
    for node in range(2):
        cmd = [sys.executable, "-m", "torch.distributed.run", "--nnodes=2", "--nproc_per_node=1",
               "--rdzv-backend=c10d", f"--rdzv-endpoint=127.0.0.1:{store.port}", "--rdzv-id=two-nodes",
               "--rdzv-conf=is_host=false", "tests/dist_worker.py", str(tmp_path), "4"]
        log = open(tmp_path / f"node{node}.log", "w")
        nodes.append(subprocess.Popen(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=ENV))
    for node, p in enumerate(nodes):
        assert p.wait(timeout=300) == 0, (tmp_path / f"node{node}.log").read_text()[-3000:]
    check_one_policy(tmp_path, 4)


def test_train_command_under_torchrun_on_the_cpu(tmp_path):
    run = tmp_path / "ant"
    # -m warpgym train, as the README writes it
    done = torchrun("-m", "warpgym", "train", "--task", "Ant", "--device", "cpu", "--num-envs", "4",
                    "--max-iterations", "2", "--horizon-len", "4", "--episode-length", "20",
                    "--no-eval", "--no-plots", "--run-dir", str(run))
    # --multi-gpu grow-kl (the default): --num-envs on each process, the KL target twice the preset's 0.008
    assert "x 2 processes, 4 envs each (--multi-gpu grow-kl: 8 in all, KL target 0.016)" in done.stdout
    summary = json.loads((run / "summary.json").read_text())
    assert (summary["iterations"], summary["workers"], summary["num_envs"], summary["num_envs_total"]) == (2, 2, 4, 8)
    assert summary["kl_target"] == pytest.approx(0.016)
    rows = (run / "metrics.jsonl").read_text().splitlines()
    assert len(rows) == 2 and '"samples": 64' in rows[1]  # 2 processes x 4 envs x 4 steps x 2 iterations


def test_a_legged_task_trains_under_torchrun_with_its_critic_statistics_shared(tmp_path):
    """The default mode on a legged task: each process its own worlds, one policy, and both normalisers (the
    policy's observation and the critic's own) counting every process's samples."""
    run = tmp_path / "go1"
    done = torchrun("-m", "warpgym", "train", "--task", "Go1VelocityFlat-v0", "--device", "cpu", "--num-envs", "4",
                    "--max-iterations", "2", "--horizon-len", "4", "--no-eval", "--no-plots", "--run-dir", str(run))
    assert "x 2 processes, 4 envs each (--multi-gpu grow-kl: 8 in all" in done.stdout
    ckpt = load(str(run / "checkpoint.pt"), torch.device("cpu"))
    assert ckpt["spec"]["num_critic_obs"] == 72
    # 2 processes x 4 envs x (the first observation + 2 iterations x 4 steps)
    samples = 2 * 4 * (1 + 2 * 4)
    assert round(float(ckpt["normalizer"]["count"])) == samples
    assert round(float(ckpt["critic_normalizer"]["count"])) == samples
    assert ckpt["critic_normalizer"]["mean"].shape == (72,)


def test_a_suite_task_trained_by_torchrun_is_scored_in_gymnasiums_env(tmp_path):
    """torchrun -m warpgym train on one of Gymnasium's tasks, its checkpoint played by warpgym eval in
    gymnasium.make's env from the same starts as in warpgym's: the returns agree."""
    run = tmp_path / "hopper"
    # split-horizon, the suite's preset: each process steps its 8 envs for 4 of the 8 steps, the one-process batch
    done = torchrun("-m", "warpgym", "train", "--task", "Hopper-v5", "--device", "cpu", "--num-envs", "8",
                    "--max-iterations", "3", "--horizon-len", "8", "--no-plots", "--run-dir", str(run))
    assert "(--multi-gpu split-horizon: 16 in all, 4 of horizon_len 8 steps each)" in done.stdout
    assert json.loads((run / "summary.json").read_text())["horizon_per_process"] == 4
    done = subprocess.run([sys.executable, "-m", "warpgym", "eval", str(run), "--episodes", "2", "--seeds", "0",
                           "--json", str(tmp_path / "eval.json")], cwd=ROOT, capture_output=True, text=True,
                          timeout=300, env=ENV)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    scored = json.loads((tmp_path / "eval.json").read_text())
    # 3 iterations of 2 processes x 8 envs x 4 steps
    assert scored["task"] == "Hopper-v5" and scored["samples"] == 3 * 2 * 8 * 4 and scored["episodes"] == 2
    assert scored["same_starts"] and abs(scored["gymnasium_over_warpgym"] - 1.0) < 1e-3


def test_a_silent_peer_is_noticed_and_a_finished_one_is_not():
    store = dist.TCPStore("127.0.0.1", 0, is_master=True, wait_for_workers=False, timeout=timedelta(seconds=10))
    lost: list[tuple[int, str]] = []
    heard = threading.Event()

    def on_lost(rank):
        def record(why):
            lost.append((rank, why))
            heard.set()
        return record

    def watches():
        return [PeerWatch(store, r, 3, interval=0.05, timeout=0.5, on_lost=on_lost(r)) for r in range(3)]

    w = watches()
    w[2].stop(finished=True)  # ended on purpose: nobody waits for it any more
    time.sleep(1.5)
    assert lost == []
    w[1].stop(finished=False)  # died: its beats stop, with no word
    assert heard.wait(5.0)
    assert lost[0][0] == 0 and "worker 1 has not been heard from" in lost[0][1]
    w[0].stop(finished=True)


def test_a_lost_peer_names_the_checkpoint_written_after_the_watch_started(tmp_path):
    """On GPUs a worker whose peer died sits in an NCCL collective until its PeerWatch ends it; the
    resume hint it prints is asked for then, not when training started (when there was no checkpoint)."""
    from warpgym.cli.train import resume_hint

    watch = PeerWatch(dist.HashStore(), 0, 2, interval=30.0, timeout=60.0, hint=lambda: resume_hint(str(tmp_path)))
    try:
        assert "No checkpoint" in watch.message("worker 1 has not been heard from for 20 s")
        (tmp_path / "checkpoint.pt").write_bytes(b"saved by iteration 3")
        assert f"--resume {tmp_path}" in watch.message("worker 1 has not been heard from for 20 s")
    finally:
        watch.stop(finished=True)


# The jobs that test how a distributed run starts, stops, fails and resumes: a suite task, which a process
# builds in half the time Newton's Ant takes on the CPU (the torchrun command above keeps the Ant)
LIFECYCLE_TASK = "HalfCheetah-v5"


def worker_pids(agent_pid: int) -> dict[int, int]:
    """RANK -> pid of the worker processes a torchrun agent started (read from /proc)."""
    found = {}
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/stat") as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
            if ppid != agent_pid:
                continue
            with open(f"/proc/{pid}/environ", "rb") as f:
                env = dict(kv.split(b"=", 1) for kv in f.read().split(b"\0") if b"=" in kv)
            found[int(env[b"RANK"])] = int(pid)
        except (OSError, KeyError, ValueError, IndexError):
            continue
    return found


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="finds the worker processes through /proc")
def test_a_killed_worker_stops_the_job_and_the_run_resumes_on_one_process(tmp_path):
    run = tmp_path / "ant"
    common = ["--horizon-len", "4", "--episode-length", "20", "--no-eval", "--no-plots"]
    log = open(tmp_path / "job.log", "w")
    job = subprocess.Popen([*torchrun_args(2), "scripts/train.py", "--task", LIFECYCLE_TASK, "--device", "cpu",
                            "--num-envs", "4", "--multi-gpu", "split", "--max-iterations", "100000", "--save-gap", "3",
                            "--run-dir", str(run), *common],
                           cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=dict(ENV, WARPGYM_PEER_TIMEOUT="20"))
    deadline = time.time() + 240
    while time.time() < deadline and job.poll() is None:
        if (run / "checkpoint.pt").exists() and (run / "metrics.jsonl").exists() and len(read_metrics(str(run))) >= 7:
            break
        time.sleep(0.2)
    assert job.poll() is None, (tmp_path / "job.log").read_text()[-3000:]
    os.kill(worker_pids(job.pid)[1], signal.SIGKILL)
    killed = time.time()
    code = job.wait(timeout=120)
    assert time.time() - killed < 60
    out = (tmp_path / "job.log").read_text()
    assert code != 0 and "--resume" in out, out[-3000:]

    saved = load(str(run / "checkpoint.pt"), torch.device("cpu"))
    start = saved["iteration"]
    # a save-gap checkpoint (a multiple of 3), or rank 0's own save when torchrun's SIGTERM reaches it after an
    # iteration it finished before the peer died: either way whole iterations of both processes
    # --multi-gpu split: --num-envs 4 is the run's total, 2 processes x 2 envs x 4 steps an iteration
    assert start >= 3 and saved["samples"] == start * 16, (start, saved["samples"])
    # the same run on one process: it goes on from the checkpoint, and rows after it are logged once
    done = subprocess.run([sys.executable, "scripts/train.py", "--resume", str(run), "--max-iterations",
                           str(start + 3)], cwd=ROOT, capture_output=True, text=True, timeout=300, env=ENV)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    assert f"resumed at iteration {start}" in done.stdout
    rows = read_metrics(str(run))
    assert [r["iteration"] for r in rows] == list(range(1, start + 4))
    assert [r["samples"] for r in rows[start:]] == [start * 16 + 16 * k for k in (1, 2, 3)]  # now 1 process x 4 envs
    assert load(str(run / "checkpoint.pt"), torch.device("cpu"))["iteration"] == start + 3


def start_job(tmp_path, name, *flags, script="scripts/train.py", env=None):
    run = tmp_path / name
    log = open(tmp_path / f"{name}.log", "w")
    job = subprocess.Popen([*torchrun_args(2), script, "--task", LIFECYCLE_TASK, "--device", "cpu", "--num-envs", "4",
                            "--horizon-len", "4", "--episode-length", "20", "--no-eval", "--no-plots",
                            "--run-dir", str(run), *flags], cwd=ROOT, stdout=log, stderr=subprocess.STDOUT,
                           env=dict(ENV, **(env or {})), start_new_session=True)
    return job, run, tmp_path / f"{name}.log"


def wait_for_rows(job, run, log, rows: int, timeout: float = 240) -> None:
    deadline = time.time() + timeout
    while time.time() < deadline and job.poll() is None:
        if (run / "metrics.jsonl").exists() and len(read_metrics(str(run))) >= rows:
            return
        time.sleep(0.2)
    raise AssertionError(f"no {rows} rows: {log.read_text()[-3000:]}")


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="finds the worker processes through /proc")
def test_finished_two_process_runs_exit_within_10_s_of_their_last_row(tmp_path):
    """A run whose time limit is read at a checkpoint iteration once left rank 0 a step ahead of the
    others: it finished while they waited in the next iteration's collectives (on GPUs, for ever).
    --save-gap 1 makes every iteration a checkpoint iteration. The time limits count from the processes' start,
    which took 7.9-14.7 s on the two-core development machine (2026-11-27), and longer beside another pytest-xdist
    worker's tests (the call-limit test's first row came 14 s in there): they are set 12-13 s past the first row of
    the run of 12 iterations, so that each run's limit ends it after several save gaps, not at its first row."""
    jobs = [("iterations", ["--save-gap", "1", "--max-iterations", "12"]),
            ("gap1", ["--save-gap", "1", "--time-limit", "+12"]), ("gap3", ["--save-gap", "3", "--time-limit", "+13"])]
    start = None
    for name, flags in jobs:
        if flags[-1].startswith("+"):  # seconds after the first run's first row
            flags = [*flags[:-1], f"{start + float(flags[-1][1:]):.1f}"]
        job, run, log = start_job(tmp_path, name, *flags)
        code = job.wait(timeout=240)
        ended = time.time()
        assert code == 0, log.read_text()[-3000:]
        last_row = os.path.getmtime(run / "metrics.jsonl")
        assert ended - last_row < 10.0, (name, ended - last_row)
        assert len(read_metrics(str(run))) >= 6, name  # the time limits ended runs of several save gaps
        saved = load(str(run / "checkpoint.pt"), torch.device("cpu"))["iteration"]
        assert saved == read_metrics(str(run))[-1]["iteration"]
        start = start or read_metrics(str(run))[0]["time_s"]


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="finds the worker processes through /proc")
def test_sigterm_to_torchrun_stops_every_process_and_names_the_resume(tmp_path):
    job, run, log = start_job(tmp_path, "term", "--max-iterations", "100000", "--save-gap", "3")
    wait_for_rows(job, run, log, 6)
    workers = worker_pids(job.pid)
    assert len(workers) == 2
    job.send_signal(signal.SIGTERM)  # a cluster's pre-emption reaches torchrun
    sent = time.time()
    job.wait(timeout=90)
    while time.time() - sent < 60 and any(os.path.exists(f"/proc/{p}") for p in workers.values()):
        time.sleep(0.2)
    assert time.time() - sent < 60 and not any(os.path.exists(f"/proc/{p}") for p in workers.values())
    out = log.read_text()
    assert f"--resume {run}" in out, out[-3000:]
    saved = load(str(run / "checkpoint.pt"), torch.device("cpu"))["iteration"]
    assert saved == read_metrics(str(run))[-1]["iteration"]  # stopped after an iteration and saved it


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="finds the worker processes through /proc")
def test_an_exception_in_one_worker_mid_update_stops_every_process(tmp_path):
    job, run, log = start_job(tmp_path, "fail", "--max-iterations", "100000", "--save-gap", "3",
                              script="tests/fail_worker.py", env={"FAIL_AT": "1:6", "WARPGYM_PEER_TIMEOUT": "20"})
    deadline = time.time() + 240
    while time.time() < deadline and "planted failure" not in log.read_text():
        time.sleep(0.2)
    failed = time.time()
    workers = worker_pids(job.pid)
    code = job.wait(timeout=120)
    while time.time() - failed < 60 and any(os.path.exists(f"/proc/{p}") for p in workers.values()):
        time.sleep(0.2)
    assert time.time() - failed < 60 and not any(os.path.exists(f"/proc/{p}") for p in workers.values())
    out = log.read_text()
    assert code != 0 and "planted failure in worker 1's update 6" in out
    assert f"--resume {run}" in out, out[-3000:]


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the processes' environments in /proc")
def test_exits_finds_the_worker_of_a_rank_by_its_environment():
    """benchmarks/reliability/exits.py kills rank 1, not whichever child /proc lists second."""
    from benchmarks.reliability.exits import rank_pid

    kids = [subprocess.Popen([sys.executable, "-c", "import time; print('up', flush=True); time.sleep(60)"],
                             env=dict(ENV, RANK=str(r)), stdout=subprocess.PIPE, text=True) for r in (1, 0)]
    try:
        for k in kids:  # a child read between fork and exec still shows this process's environment
            assert k.stdout.readline().strip() == "up"
        pids = [k.pid for k in kids]
        assert rank_pid(pids, 1) == kids[0].pid and rank_pid(pids, 0) == kids[1].pid
        assert rank_pid(pids, 2) is None
    finally:
        for k in kids:
            k.kill()
            k.wait()
            k.stdout.close()


def test_a_failure_that_was_not_made_does_not_hold():
    from benchmarks.reliability.exits import holds

    stopped = {"kind": "killed-rank", "all_stopped_s": 30.2, "names_resume": True}
    assert holds(stopped) and holds({**stopped, "made": True}) and not holds({**stopped, "made": False})


def test_every_benchmark_child_that_may_run_nccl_has_nvlink_multicast_off(tmp_path, monkeypatch):
    """The lending host's rule: exits.py's and nodes.py's torchrun jobs, like gpu_jobs', and the suite's one-GPU runs
    (harness.gpu_slot) start with multicast off, whatever the caller's environment says."""
    import argparse

    from benchmarks import harness
    from benchmarks.multi_gpu import nodes
    from benchmarks.reliability import exits

    monkeypatch.setenv("NCCL_NVLS_ENABLE", "1")
    seen = []

    class Recorded:
        pid, returncode = 0, 0

        def __init__(self, cmd, **kw):
            seen.append(kw["env"])

        def wait(self, timeout=None):
            return 0

    monkeypatch.setattr(subprocess, "Popen", Recorded)
    args = argparse.Namespace(out=str(tmp_path), gpus=2, device="cpu", num_envs=None, task="Ant", seconds=1.0,
                              seed=0, tasks=["Ant"])
    exits.Job(args, "one", "Ant", []).log.close()
    nodes.run_layout(args, "r0-2node", 2)
    seen.append(harness.gpu_slot(0, 1)["env"])  # the suite's one-GPU runs, side by side on a host
    assert len(seen) == 4 and all({k: env[k] for k in harness.NO_MULTICAST} == harness.NO_MULTICAST for env in seen)
