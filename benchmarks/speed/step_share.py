"""warpgym's own share of a legged step, two ways, on one model of ``--num-envs`` worlds:

- by rate: the env's captured step (pre-drawn random actions in [-1, 1]) against MuJoCo Warp's own work on the very
  worlds the env stepped: each of the env's steps recorded (the state it started from, the controls its actions
  set), then replayed as a graph of a copy-in, ``decimation`` MuJoCo Warp steps and one forward pass, the physics
  every step of the task needs and nothing else. A loop that steps the env's states on constant controls instead
  lets MuJoCo Warp's solver settle in fewer iterations than the env's fresh targets allow, and so overstates the
  env's own share;
- by GPU time: every kernel of the uncaptured step timed by Warp's CUDA activity timer, warpgym's kernels apart.

    python -m benchmarks.speed.step_share --tasks Go1VelocityFlat-v0 G1VelocityFlat-v0 --num-envs 4096 \\
        --out OUT/share.json

It reads only what every warpgym since the legged tasks came has (the env's sim, index, state and step), so
``benchmarks.speed.before_after`` runs it against an older checkout too.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys

import torch
import warp as wp

wp.set_module_options({"enable_backward": False})


@wp.kernel
def load_recorded(k: wp.array[wp.int32], qpos_rec: wp.array3d[float], qvel_rec: wp.array3d[float],
                  warm_rec: wp.array3d[float], ctrl_rec: wp.array3d[float], qpos: wp.array2d[float],
                  qvel: wp.array2d[float], warm: wp.array2d[float], ctrl: wp.array2d[float]):
    """World w's state and controls as the env's step ``k[0]`` started."""
    w = wp.tid()
    s = k[0]
    for i in range(qpos.shape[1]):
        qpos[w, i] = qpos_rec[s, w, i]
    for i in range(qvel.shape[1]):
        qvel[w, i] = qvel_rec[s, w, i]
        warm[w, i] = warm_rec[s, w, i]
    for i in range(ctrl.shape[1]):
        ctrl[w, i] = ctrl_rec[s, w, i]


@wp.kernel
def next_recorded(k: wp.array[wp.int32], count: int):
    k[0] = (k[0] + 1) % count


def seconds(fn, count: int, device: str) -> float:
    """Seconds of ``count`` calls, the device drained before and after (warpgym's one step timer; every checkout
    this runs against has it)."""
    from warpgym.cli.bench import timed  # noqa: PLC0415

    return timed(fn, count, 1, device)[0]


def our_kernel_keys() -> set[str]:
    """The keys of warpgym's own Warp kernels (every kernel of a loaded module of kernels/ or warpgym/, and the
    kernels the legged step makes from its tables); the other kernels of a step are MuJoCo Warp's."""
    keys = {"step_kernels__locals__"}
    for name, module in list(sys.modules.items()):
        if module is None or not name.startswith(("kernels", "warpgym")):
            continue
        for value in list(vars(module).values()):
            if isinstance(value, wp.Kernel):
                keys.add(value.key.replace(".", "__").replace("<", "").replace(">", "") + "_")
    return keys


def share(task: str, num_envs: int, steps: int, repeats: int, device: str) -> dict:
    from warpgym.envs.legged import LeggedVecEnv  # noqa: PLC0415
    from warpgym.sim.mjw_internals import mujoco_contact_frames  # noqa: PLC0415

    import mujoco_warp as mjw  # noqa: PLC0415

    env = LeggedVecEnv(task, num_envs=num_envs, device=device, seed=0)
    env.reset(seed=0)
    sim, idx, t = env.sim, env.index, env.sim.to_torch
    gen = torch.Generator(device=env.device).manual_seed(0)
    actions = [torch.rand(num_envs, env.num_actions, device=env.device, generator=gen) * 2 - 1 for _ in range(steps)]
    for a in actions[:50]:
        env.step(a)
    views = [t(sim.d.qpos), t(sim.d.qvel), t(sim.d.qacc_warmstart)]
    rec = [torch.zeros((steps, *v.shape), device=env.device) for v in views]
    rec_ctrl = torch.zeros((steps, num_envs, sim.nu), device=env.device)
    act = torch.as_tensor(idx.joint_actuator, device=env.device).long()
    scale = torch.as_tensor(idx.action_scale, device=env.device)
    default = torch.as_tensor(idx.default_joint_pos, device=env.device)
    counter = wp.zeros(1, dtype=wp.int32, device=sim.device)
    w = [wp.from_torch(r) for r in (*rec, rec_ctrl)]

    def replay():
        with wp.ScopedDevice(sim.device), mujoco_contact_frames():
            wp.launch(load_recorded, dim=num_envs, inputs=[counter, *w, sim.d.qpos, sim.d.qvel, sim.d.qacc_warmstart,
                                                           sim.d.ctrl])
            for _ in range(sim.frame_skip):
                mjw.step(sim.m, sim.d)
            mjw.forward(sim.m, sim.d)
            wp.launch(next_recorded, dim=1, inputs=[counter, steps])

    graph = sim.capture(replay)

    def replay_step():
        sim.launch(graph, replay)

    k = [0]

    def env_step():
        env.step(actions[k[0] % steps])
        k[0] += 1

    env_rates, physics_rates = [], []
    for _ in range(repeats):
        env_rates.append(num_envs * steps / seconds(env_step, steps, device))
        bias = env.state()["encoder_bias"].to(env.device)
        for i in range(steps):  # the worlds as each step starts, and the controls its actions set
            for r, v in zip(rec, views):
                r[i].copy_(v)
            rec_ctrl[i].zero_()
            rec_ctrl[i][:, act] = actions[i] * scale + default - bias
            env.step(actions[i])
        snapshot = [v.clone() for v in views]
        counter.zero_()
        physics_rates.append(num_envs * steps / seconds(replay_step, steps, device))
        for v, s in zip(views, snapshot):  # the env goes on from its own state
            v.copy_(s)
    out = {"task": task, "num_envs": num_envs, "steps": steps, "repeats": repeats,
           "env_steps_per_s": statistics.median(env_rates), "mjwarp_steps_per_s": statistics.median(physics_rates),
           "env_rates": env_rates, "mjwarp_rates": physics_rates}
    out["own_share_by_rate"] = 1.0 - out["env_steps_per_s"] / out["mjwarp_steps_per_s"]
    if device.startswith("cuda"):
        wp.synchronize_device(sim.device)
        wp.timing_begin(cuda_filter=wp.TIMING_KERNEL)
        for i in range(steps):
            env._actions_in_t.copy_(actions[i])
            sim.launch(None, env._launch_step)
        results = wp.timing_end()
        ours, per_kernel = our_kernel_keys(), {}
        for r in results:
            per_kernel[r.name] = per_kernel.get(r.name, 0.0) + r.elapsed / steps
        mine = {n: ms for n, ms in per_kernel.items() if any(n.split(" ")[-1].startswith(k) for k in ours)}
        total = sum(per_kernel.values())
        out.update(gpu_ms_per_step=total, own_gpu_ms_per_step=sum(mine.values()),
                   own_share_of_gpu_time=sum(mine.values()) / total,
                   own_kernels_ms=dict(sorted(mine.items(), key=lambda kv: -kv[1])))
    env.close()
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.speed.step_share", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", nargs="+", default=["Go1VelocityFlat-v0", "G1VelocityFlat-v0"])
    ap.add_argument("--num-envs", nargs="+", type=int, default=[4096])
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--device", default="cuda:0")
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    rows = [share(t, n, args.steps, args.repeats, args.device) for t in args.tasks for n in args.num_envs]
    for r in rows:
        line = (f"{r['task']} at {r['num_envs']} envs: env {r['env_steps_per_s'] / 1e6:.3f} M/s, MuJoCo Warp on the "
                f"same worlds {r['mjwarp_steps_per_s'] / 1e6:.3f} M/s: own share {r['own_share_by_rate']:.1%}")
        if "own_share_of_gpu_time" in r:
            line += (f"; warpgym's kernels {r['own_gpu_ms_per_step'] * 1e3:.0f} us of {r['gpu_ms_per_step']:.2f} ms "
                     f"GPU time a step ({r['own_share_of_gpu_time']:.1%})")
        print(line, flush=True)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(rows, f, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
