"""Throughput of the legged velocity tasks (``warpgym bench --legged Go1VelocityFlat-v0 ...``), in env-steps per
second, two loops on one model of ``num_envs`` worlds:
  env     ``LeggedVecEnv.step`` with uniform random actions in [-1, 1], drawn each step as mjlab's bare-step
          measurement draws them (benchmarks/physics/mjlab_side.py ``speed``): actions in, ``decimation`` physics
          steps, rewards, terminations, pushes, resets, the forward pass, commands and both observations, one graph;
  mjwarp  MuJoCo Warp's own step ``decimation`` times and one forward pass, graph-captured, from the env's states:
          the physics every step of the task needs, nothing else (the ceiling warpgym's step can reach).
"""

from __future__ import annotations

import time

import torch

from warpgym.cli.bench.suite import mujoco_warp_loop
from warpgym.envs.legged import LeggedVecEnv


def _seconds(fn, steps: int, device: str) -> float:
    """Seconds of ``steps`` calls of ``fn``: ``warpgym.cli.bench.timed``, the one step timer, once."""
    from warpgym.cli.bench import timed  # noqa: PLC0415

    return timed(fn, steps, 1, device)[0]


def bench_legged_task(task: str, num_envs: int, device: str, steps: int, warmup: int, repeats: int,
                      njmax: int | None = None) -> dict:
    """``njmax``: constraint rows per world MuJoCo Warp makes room for (default: the task's, mjlab's 300)."""
    from warpgym.cli.bench import gpu_memory_used as memory_used  # noqa: PLC0415

    before = memory_used(device)
    start = time.perf_counter()
    env = LeggedVecEnv(task, num_envs=num_envs, device=device, seed=0, **({"njmax": njmax} if njmax else {}))
    env.reset(seed=0)
    built = time.perf_counter() - start
    mem = memory_used(device) - before
    def env_step():
        env.step(torch.rand(num_envs, env.num_actions, device=env.device) * 2 - 1)

    rates, physics = [], []
    raw = None
    d = env.sim.d
    for _ in range(repeats):
        for _ in range(warmup):
            env_step()
        # the physics alone from the same states as the env's timing that follows
        start = [a.numpy().copy() for a in (d.qpos, d.qvel, d.qacc_warmstart, d.ctrl)]
        raw = raw or mujoco_warp_loop(env, forward=True)
        raw()
        physics.append(num_envs * steps / _seconds(raw, steps, device))
        for a, value in zip((d.qpos, d.qvel, d.qacc_warmstart, d.ctrl), start):
            a.assign(value)
        rates.append(num_envs * steps / _seconds(env_step, steps, device))
    faults = {name: int(v) for name, v in env.fault_counters().items()}
    load = env.sim.solver_load()
    env.close()
    return {"task": task, "num_envs": num_envs, "njmax": env.task.njmax, "env_steps_per_s": rates, "mjwarp_steps_per_s": physics, "build_s": built,
            "gpu_mem_mib": mem / 2**20, "faults": faults, "solver_load": load}
