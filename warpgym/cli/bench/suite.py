"""Throughput of Gymnasium's MuJoCo tasks (``warpgym bench --tasks Hopper-v5 ...``), in env-steps
per second, two loops on one model of ``num_envs`` worlds:
  mjwarp  MuJoCo Warp's own step of the file's model, ``frame_skip`` times, graph-captured: the limit
          warpgym builds on (no actions, observations, rewards or resets; no contact forces), timed from
          the same states as the env's timings;
  env     SuiteVecEnv.step(random actions): actions in, physics, Gymnasium's observation, reward,
          termination and the resets of finished worlds, one graph.
"""

from __future__ import annotations

import torch
import warp as wp

from warpgym.envs.suite import SuiteVecEnv
from warpgym.sim.mjw_internals import mujoco_contact_frames


def mujoco_warp_loop(env, forward: bool = False):
    """MuJoCo Warp's step alone on the env's data, ``frame_skip`` times per call (and a forward pass after them with
    ``forward``, as the legged tasks' step has), captured once."""
    import mujoco_warp  # noqa: PLC0415

    sim = env.sim

    def steps():
        with wp.ScopedDevice(sim.device), mujoco_contact_frames():
            for _ in range(sim.frame_skip):
                mujoco_warp.step(sim.m, sim.d)
            if forward:
                mujoco_warp.forward(sim.m, sim.d)

    graph = sim.capture(steps)
    return steps if graph is None else (lambda: wp.capture_launch(graph))


def bench_suite_task(task: str, num_envs: int, device: str, steps: int, warmup: int, repeats: int,
                     njmax: int | None = None) -> dict:
    """Median env-steps/s of MuJoCo Warp's step and of the task's whole step on ``num_envs`` worlds, after ``warmup``
    steps (the capture, the first resets). The suite keeps the file's own compile: ``njmax`` is refused."""
    from warpgym.cli.bench import gpu_memory_used as memory_used, timed  # noqa: PLC0415

    if njmax is not None:
        raise ValueError(f"njmax={njmax}: {task} runs MuJoCo's compile of Gymnasium's file as it is; leave --njmax out")
    before = memory_used(device)
    env = SuiteVecEnv(task, num_envs=num_envs, device=device, seed=0)
    env.reset(seed=0)
    low = torch.as_tensor(env.single_action_space.low, device=env.device)
    high = torch.as_tensor(env.single_action_space.high, device=env.device)
    pool = [low + (high - low) * torch.rand(num_envs, env.num_actions, device=env.device) for _ in range(8)]
    k = [0]

    def env_step():
        env.step(pool[k[0] % len(pool)])
        k[0] += 1

    for _ in range(warmup):
        env_step()
    mem = memory_used(device) - before
    raw = mujoco_warp_loop(env)
    raw()
    # Both loops start each timing from the same state (qpos, qvel, warm start), taken after the warm-up:
    # timed one after the other from wherever the last left the worlds, they would step different states
    # (robots the env would have reset lie in contact in the raw loop) and their ratio would measure that.
    d = env.sim.d
    start = [a.numpy().copy() for a in (d.qpos, d.qvel, d.qacc_warmstart)]

    def restore():
        for a, value in zip((d.qpos, d.qvel, d.qacc_warmstart), start):
            a.assign(value)
        wp.synchronize_device(device)

    env_s, raw_s = [], []
    for _ in range(repeats):
        restore()
        env_s += timed(env_step, steps, 1, device)
        restore()
        raw_s += timed(raw, steps, 1, device)
    med = sorted(env_s)[len(env_s) // 2], sorted(raw_s)[len(raw_s) // 2]
    faults = {name: int(v) for name, v in env.fault_counters().items()}
    load = env.sim.solver_load()
    env.close()
    return {"task": task, "num_envs": num_envs, "njmax": None, "frame_skip": env.sim.frame_skip,
            "env_steps_per_s": num_envs * steps / med[0], "mjwarp_steps_per_s": num_envs * steps / med[1],
            "env_over_mjwarp": med[1] / med[0], "env_seconds": env_s, "mjwarp_seconds": raw_s,
            "gpu_mem_mib": mem / 2**20, "faults": faults, "solver_load": load}
