"""What the benchmarks share: where the repository is, how a training is started and its summary read,
JSON written whole, and a GPU with its share of the host's cores for a child process."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import subprocess
import sys
import threading

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


@contextlib.contextmanager
def waits_out_sigterm(forward=None):
    """While the block waits for child processes, a SIGTERM (a device call's `timeout`) does not end this one:
    ``forward()`` runs at the first (to pass it on once: a training stopped twice stops unsaved), the block goes on
    until its children have saved and ended, and leaving it exits 143. Yields the signals heard, for loops that
    should start nothing more. Off the main thread, where no handler can be set, it changes nothing."""
    heard: list[int] = []
    main = threading.current_thread() is threading.main_thread()

    def on_term(signum, frame):
        if not heard and forward is not None:
            forward()
        heard.append(signum)

    previous = signal.signal(signal.SIGTERM, on_term) if main else None
    try:
        yield heard
    finally:
        if main:
            signal.signal(signal.SIGTERM, previous)
    if heard:
        raise SystemExit(128 + signal.SIGTERM)


def train_in_parts(args: list[str], run_dir: str, resume_args: list[str], device: str | None = None) -> int:
    """``warpgym train ARGS --run-dir RUN_DIR --no-plots``, its output appended to RUN_DIR/train.log; its exit code.

    A run longer than a machine's call limit (a device call's 10 minutes against a 10-minute run) trains in parts:
    stopped by SIGTERM, the training saves its last iteration and this waits for it, then exits 143; called again
    with the same ``run_dir`` it goes on with ``warpgym train --resume RUN_DIR RESUME_ARGS`` (its clock, marks and
    rows carry on), and a run that had ended on its own is not trained again (0 at once). A folder without a
    checkpoint (stopped before its first save) starts afresh."""
    has = lambda name: os.path.isfile(os.path.join(run_dir, name))  # noqa: E731
    if has("checkpoint.pt") and has("config.json"):
        if has("summary.json") and not read_summary(run_dir).get("stopped_on_request", False):
            return 0  # ended by its own budget: done
        cmd = [*TRAIN, "--resume", run_dir, *resume_args, "--no-plots"]
    else:
        shutil.rmtree(run_dir, ignore_errors=True)
        cmd = [*TRAIN, *args, "--run-dir", run_dir, "--no-plots"]
    os.makedirs(run_dir, exist_ok=True)
    with open(os.path.join(run_dir, "train.log"), "a") as log:
        # In its own session, a SIGTERM to this process group (`timeout`'s) reaches the training once, from here: a
        # second one would stop it at once, unsaved. Off the main thread it stays in the group and gets it directly.
        main = threading.current_thread() is threading.main_thread()
        child = subprocess.Popen(cmd + (["--device", device] if device else []), cwd=ROOT, stdout=log,
                                 stderr=subprocess.STDOUT, start_new_session=main)
        with waits_out_sigterm(lambda: child.send_signal(signal.SIGTERM)):  # it saves its iteration; this waits
            return child.wait()


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


def read_report(path: str, what: str, flag: str = "--report") -> dict:
    """The JSON an earlier run of a benchmark wrote, for its ``--report`` (or the ``flag`` that reads one); a missing
    or damaged file ends the process with one line naming it and ``what`` to pass instead."""
    try:
        with open(path) as f:
            return json.load(f)
    except FileNotFoundError:
        raise SystemExit(f"{flag} {path}: no such file; pass {what}") from None
    except (OSError, ValueError) as e:
        raise SystemExit(f"{flag} {path}: cannot be read as JSON ({e}); pass {what}") from None


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
           "waits_out_sigterm", "write_json"]
