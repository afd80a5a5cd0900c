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


__all__ = ["NO_MULTICAST", "ROOT", "TRAIN", "child_env", "core_shares", "gpu_slot", "read_report", "read_summary", "reported", "visible_gpus", "write_json"]
