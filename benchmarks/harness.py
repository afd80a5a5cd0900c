"""What the benchmarks share: where the repository is, how a training is started and its summary read,
JSON written whole, and a GPU with its share of the host's cores for a child process."""

from __future__ import annotations

import json
import os
import sys

from warpgym.cli import write_json

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # the repository
# `warpgym train` as a child process, however warpgym is installed (a checkout or a wheel)
TRAIN = [sys.executable, "-m", "warpgym", "train"]
# NVLink multicast stays off in every child that may run NCCL (the lending host's rule: a program that uses it
# can take the host's GPUs out of service), also where a job is given an environment of its own
NO_MULTICAST = {"NCCL_NVLS_ENABLE": "0", "TORCH_SYMM_MEM_DISABLE_MULTICAST": "1", "NVSHMEM_DISABLE_NVLS": "1"}


def child_env(**extra: str) -> dict:
    """The environment of a benchmark's child process: this one's, ``extra``, and multicast off."""
    return {**os.environ, **extra, **NO_MULTICAST}


def read_summary(run_dir: str) -> dict:
    """A finished run's summary.json."""
    with open(os.path.join(run_dir, "summary.json")) as f:
        return json.load(f)


def train_in_parts(args: list[str], run_dir: str, resume_args: list[str], device: str | None = None) -> int:
    """``warpgym train ARGS --run-dir RUN_DIR --no-plots``, its output appended to RUN_DIR/train.log; its exit code.

    A run longer than a machine's call limit (a device call's 10 minutes against a 10-minute run) trains in parts:
    stopped by SIGTERM, the training saves its last iteration and this waits for it, then exits 143; called again
    with the same ``run_dir`` it goes on with ``warpgym train --resume RUN_DIR RESUME_ARGS`` (its clock, marks and
    rows carry on), and a run that had ended on its own is not trained again (0 at once). A folder without a
    checkpoint (stopped before its first save) starts afresh."""
    import shutil  # noqa: PLC0415
    import signal  # noqa: PLC0415
    import subprocess  # noqa: PLC0415
    import threading  # noqa: PLC0415

    has = lambda name: os.path.isfile(os.path.join(run_dir, name))  # noqa: E731
    if has("checkpoint.pt") and has("config.json"):
        if has("summary.json") and not read_summary(run_dir).get("stopped_on_request", False):
            return 0  # ended by its own budget: done
        cmd = [*TRAIN, "--resume", run_dir, *resume_args, "--no-plots"]
    else:
        shutil.rmtree(run_dir, ignore_errors=True)
        cmd = [*TRAIN, *args, "--run-dir", run_dir, "--no-plots"]
    os.makedirs(run_dir, exist_ok=True)
    stopped = []
    with open(os.path.join(run_dir, "train.log"), "a") as log:
        main = threading.current_thread() is threading.main_thread()  # only the main thread may set handlers
        # In its own session, a SIGTERM to this process group (`timeout`'s) reaches the training once, from here: a
        # second one would stop it at once, unsaved. Off the main thread it stays in the group and gets it directly.
        child = subprocess.Popen(cmd + (["--device", device] if device else []), cwd=ROOT, stdout=log,
                                 stderr=subprocess.STDOUT, start_new_session=main)

        def forward(signum, frame):  # the training saves its iteration; this waits for it below
            if not stopped:  # once: a second SIGTERM would stop it unsaved
                child.send_signal(signal.SIGTERM)
            stopped.append(signum)

        previous = signal.signal(signal.SIGTERM, forward) if main else None
        try:
            code = child.wait()
        finally:
            if main:
                signal.signal(signal.SIGTERM, previous)
    if stopped:
        raise SystemExit(128 + signal.SIGTERM)
    return code


def visible_gpus(count: int) -> list[str]:
    """The ids of the first ``count`` GPUs this process may hand out (``CUDA_VISIBLE_DEVICES``, or 0..count-1)."""
    visible = [d.strip() for d in os.environ.get("CUDA_VISIBLE_DEVICES", "").split(",") if d.strip()]
    if visible and len(visible) < count:
        raise SystemExit(f"{count} GPUs asked for, but CUDA_VISIBLE_DEVICES={','.join(visible)} gives this process "
                         f"{len(visible)}: name more there or ask for fewer")
    return visible[:count] if visible else [str(k) for k in range(count)]


def core_shares(gpus: int, cores: list[int] | None = None) -> list[list[int]]:
    """Each of ``gpus`` GPUs' equal share of the cores this process may use (``taskset`` narrows them)."""
    cores = sorted(cores if cores is not None else os.sched_getaffinity(0))
    share = len(cores) // gpus
    if share < 1:
        raise SystemExit(f"{gpus} GPUs but only {len(cores)} cores for them: use fewer GPUs or more cores")
    return [cores[k * share:(k + 1) * share] for k in range(gpus)]


def gpu_slot(gpu: int, gpus: int) -> dict:
    """``subprocess`` arguments that give a child GPU ``gpu`` of ``gpus`` and that GPU's share of the cores, so
    that one GPU's run does not take another's CPU; under ``CUDA_VISIBLE_DEVICES=2,3`` and ``taskset`` two
    commands share a host, each on its own GPUs and cores."""
    ids, mine = visible_gpus(gpus), set(core_shares(gpus)[gpu])
    return {"env": child_env(CUDA_VISIBLE_DEVICES=ids[gpu]), "preexec_fn": lambda: os.sched_setaffinity(0, mine)}


def read_report(path: str, what: str) -> dict:
    """The JSON an earlier run of a benchmark wrote, for its ``--report``; a missing or damaged file ends the
    process with one line naming it and ``what`` to pass instead."""
    try:
        with open(path) as f:
            return json.load(f)
    except FileNotFoundError:
        raise SystemExit(f"--report {path}: no such file; pass {what}") from None
    except (OSError, ValueError) as e:
        raise SystemExit(f"--report {path}: cannot be read as JSON ({e}); pass {what}") from None


def reported(ap, args, report, what: str) -> bool:
    """A benchmark's two modes: with ``--report`` print ``report(args.report)`` and say so; else ``--out`` is needed
    (``what`` names the file --report reads, for the error)."""
    if args.report:
        print(report(args.report))
        return True
    if not args.out:
        ap.error(f"--out is required (or --report {what})")
    return False


__all__ = ["NO_MULTICAST", "ROOT", "TRAIN", "child_env", "core_shares", "gpu_slot", "read_report", "read_summary", "reported", "train_in_parts", "visible_gpus",
           "write_json"]
