"""Run jobs of 1..G GPUs on one host, side by side where they fit, each on its own GPUs and cores.

A job that needs n GPUs starts, in the order given, as soon as n GPUs are free, with
``CUDA_VISIBLE_DEVICES`` naming them and its affinity set to those GPUs' share of the cores (the cores
this process may use, divided equally among the GPUs it may use), so runs side by side take neither
each other's GPU nor each other's CPU. A job never overtakes an earlier one: a 4-GPU job waits for
the host to empty and then runs alone. The GPUs are those ``CUDA_VISIBLE_DEVICES`` gives this process,
or the first ``gpus`` of the host.
"""

from __future__ import annotations

import os
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field

from benchmarks.harness import child_env, core_shares, visible_gpus


@dataclass
class Job:
    name: str
    gpus: int
    cmd: list[str]
    log: str
    cwd: str | None = None
    env: dict = field(default_factory=dict)


def run_jobs(jobs: list[Job], gpus: int, on_done: Callable[[Job, int], None] | None = None,
             say: Callable[[str], None] = print, poll: float = 0.5, cores: list[int] | None = None) -> dict[str, int]:
    """Run ``jobs`` on ``gpus`` GPUs as described above; ``on_done(job, returncode)`` as each ends. Returns
    every job's exit code by name."""
    too_big = [j.name for j in jobs if j.gpus > gpus or j.gpus < 1]
    if too_big:
        raise SystemExit(f"jobs {too_big} need more GPUs than the {gpus} given (or none)")
    ids, shares = visible_gpus(gpus), core_shares(gpus, cores)
    free = list(range(gpus))
    pending = list(jobs)
    running: list[tuple[subprocess.Popen, Job, list[int], object]] = []
    codes: dict[str, int] = {}
    try:
        while pending or running:
            while pending and pending[0].gpus <= len(free):
                job = pending.pop(0)
                mine, free = free[:job.gpus], free[job.gpus:]
                mask = {c for k in mine for c in shares[k]}
                env = child_env(**job.env, CUDA_VISIBLE_DEVICES=",".join(ids[k] for k in mine))
                os.makedirs(os.path.dirname(os.path.abspath(job.log)), exist_ok=True)
                log = open(job.log, "w")  # noqa: SIM115 (closed when the job ends)
                proc = subprocess.Popen(job.cmd, cwd=job.cwd, stdout=log, stderr=subprocess.STDOUT, env=env,
                                        preexec_fn=lambda m=mask: os.sched_setaffinity(0, m))
                running.append((proc, job, mine, log))
                say(f"started {job.name} on GPU {','.join(ids[k] for k in mine)} ({len(mask)} cores)")
            time.sleep(poll)
            for item in [r for r in running if r[0].poll() is not None]:
                proc, job, mine, log = item
                running.remove(item)
                log.close()
                free = sorted(free + mine)
                codes[job.name] = proc.returncode
                say(f"{job.name} ended ({proc.returncode})")
                if on_done is not None:
                    on_done(job, proc.returncode)
    finally:
        for proc, _, _, log in running:  # interrupted: no job outlives this process
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
            log.close()
    return codes
