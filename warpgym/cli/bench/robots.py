"""``warpgym bench`` of warpgym's Ant and Humanoid: MuJoCo Warp's own step, Newton's solver loop, warpgym's physics
and the whole env, timed on one model (the command's ``--robots`` table, and its ``--tasks`` row)."""

from __future__ import annotations

import statistics
import time

import torch
import warp as wp

from warpgym.cli.bench import gpu_memory_used, timed
from warpgym.envs.robots import LocomotionVecEnv
from warpgym.sim import newton_internals

TASK_OF_ROBOT = {"ant": "Ant", "humanoid": "Humanoid"}


def raw_newton_loop(sim):
    """Newton's own pattern: two states swapped each substep, captured once as a graph."""
    s0, s1 = sim.model.state(), sim.model.state()
    wp.copy(s0.joint_q, sim.state.joint_q)
    wp.copy(s0.joint_qd, sim.state.joint_qd)
    states = [s0, s1]

    def substeps():
        for _ in range(sim.substeps):
            sim.solver.step(states[0], states[1], sim.control, None, sim.sub_dt)
            states.reverse()

    graph = sim.capture(substeps)
    if graph is None:
        return substeps

    def launch():
        wp.capture_launch(graph)

    launch.keep_alive = states  # the graph holds raw pointers into these states
    return launch


def mujoco_warp_loop(sim):
    """MuJoCo Warp's step alone, ``substeps`` times, without contact forces, captured once."""
    import mujoco_warp  # noqa: PLC0415

    m, d = sim.solver.mjw_model, sim.solver.mjw_data

    def substeps():
        m.opt.run_rne_postconstraint = False
        # under the solver's compile options, so these are the very kernels Sim.simulate launches
        with newton_internals.compile_options(sim.solver, sim.device):
            for _ in range(sim.substeps):
                mujoco_warp.step(m, d)

    graph = sim.capture(substeps)
    return substeps if graph is None else (lambda: wp.capture_launch(graph))


def bench_one(robot: str, num_envs: int, device: str, steps: int, repeats: int, physics: dict,
              njmax: int | None = None, warmup: int = 3) -> dict:
    mem0 = gpu_memory_used(device)
    t0 = time.perf_counter()
    env = LocomotionVecEnv(TASK_OF_ROBOT[robot], num_envs=num_envs, device=device, seed=0,
                           physics=physics, sim_options={"njmax": njmax})
    build_s = time.perf_counter() - t0
    sim = env.sim
    gen = torch.Generator(device=device).manual_seed(0)
    actions = [torch.rand(num_envs, env.num_actions, device=device, generator=gen) * 2 - 1 for _ in range(8)]
    k = [0]

    def env_step():
        env.step(actions[k[0] % 8])
        k[0] += 1

    t0 = time.perf_counter()
    for _ in range(warmup):  # compile kernels and capture graphs outside the timings
        env_step()
        sim.step()
    raw = raw_newton_loop(sim)
    raw()
    mjwarp = mujoco_warp_loop(sim)
    mjwarp()
    wp.synchronize_device(device)
    warmup_s = time.perf_counter() - t0
    mem1 = gpu_memory_used(device)

    result = {"robot": robot, "num_envs": num_envs, "njmax": sim.njmax, "steps": steps, "repeats": repeats,
              "build_s": round(build_s, 2), "warmup_s": round(warmup_s, 2),
              "gpu_mem_mib": round((mem1 - mem0) / 2**20, 1)}
    for name, fn in (("mjwarp", mjwarp), ("raw", raw), ("physics", sim.step), ("env", env_step)):
        fn()
        times = timed(fn, steps, repeats, device)
        med = statistics.median(times)
        result[f"{name}_steps_per_s"] = num_envs * steps / med
        result[f"{name}_spread"] = (max(times) - min(times)) / med
    result["raw_over_mjwarp"] = result["raw_steps_per_s"] / result["mjwarp_steps_per_s"]
    result["physics_over_raw"] = result["physics_steps_per_s"] / result["raw_steps_per_s"]
    result["env_over_physics"] = result["env_steps_per_s"] / result["physics_steps_per_s"]
    env.close()
    # drop every reference, env_step's closure cell among them, so that the next size's memory reading starts clean
    env = sim = raw = mjwarp = None
    return result


def bench_robot_task(task: str, num_envs: int, device: str, steps: int, warmup: int, repeats: int,
                     njmax: int | None = None) -> dict:
    """``bench_one`` of a robot task (Ant, Humanoid) as ``--tasks`` times it: its default physics."""
    return {"task": task, **bench_one(task.lower(), num_envs, device, steps, repeats, {}, njmax, warmup)}
