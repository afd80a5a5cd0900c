"""Throughput of the simulation, in env-steps per second (one env-step = one control step of one env).

For each robot and env count, one model is built and four loops are timed on it:
  mjwarp   MuJoCo Warp's own step on the solver's data, no Newton state in or out (what Newton's
           conversions cost), graph-captured;
  raw      Newton's SolverMuJoCo alone: the usual double-buffered substep loop, graph-captured;
  physics  warpgym.Sim.step(): the same substeps as the Sim runs them (in place, one graph);
  env      LocomotionVecEnv.step(random actions): actions in, physics, task kernels, resets.
Each figure is the median of --repeats timings of --steps steps, after a warm-up. --physics
NAME=VALUE (repeatable) times other solver settings, e.g. --physics ls_iterations=2.

    warpgym bench --robots ant humanoid --num-envs 1024 4096 16384

``--tasks`` times any task's whole step beside MuJoCo Warp's own step of the same worlds, each family as its registry
entry's ``bench`` says (each family's module beside this one: robots.py, the loops above; suite.py; legged.py), in
one table:

    warpgym bench --tasks Hopper-v5 Go1VelocityFlat-v0 Ant --num-envs 4096 8192
"""

from __future__ import annotations

import json
import os
import platform
import statistics
import sys
import time

import torch
import warp as wp

from warpgym.cli import write_json
from warpgym.cli.flags import CommandParser, check_device, positive_int
from warpgym.sim.device import resolve_device
from warpgym.sim.physics import Physics, parse_setting

def timed(fn, steps: int, repeats: int, device: str) -> list[float]:
    """Seconds per ``steps`` calls of ``fn``, ``repeats`` times, device-synchronised."""
    out = []
    for _ in range(repeats):
        wp.synchronize_device(device)
        if device.startswith("cuda"):
            torch.cuda.synchronize(device)
        t0 = time.perf_counter()
        for _ in range(steps):
            fn()
        wp.synchronize_device(device)
        if device.startswith("cuda"):
            torch.cuda.synchronize(device)
        out.append(time.perf_counter() - t0)
    return out


def gpu_memory_used(device: str) -> int:
    if not device.startswith("cuda"):
        return 0
    free, total = torch.cuda.mem_get_info(torch.device(device))
    return total - free


def parser() -> CommandParser:
    ap = CommandParser(prog="warpgym bench", description=__doc__)
    ap.add_argument("--robots", nargs="+", default=["ant", "humanoid"], choices=["ant", "humanoid"])
    ap.add_argument("--tasks", nargs="+", default=None, metavar="NAME",
                    help="tasks of any family instead of the robots (Hopper-v5, Go1VelocityFlat-v0, Ant, module:Name): "
                         "the task's step with random actions against MuJoCo Warp's own step of the same worlds")
    ap.add_argument("--legged", nargs="+", default=None, metavar="NAME-v0",
                    help="the same as --tasks (kept for the scripts that time older commits with it)")
    ap.add_argument("--warmup", type=positive_int(20), default=20,
                    help="--tasks: steps before the timings (--robots: 3)")
    ap.add_argument("--num-envs", nargs="+", type=positive_int(4096), default=[1024, 4096, 16384])
    ap.add_argument("--device", default=None)
    ap.add_argument("--steps", type=positive_int(200), default=200, help="steps per timing")
    ap.add_argument("--repeats", type=positive_int(5), default=5, help="timings per figure; the median is reported")
    ap.add_argument("--physics", action="append", default=[], metavar="NAME=VALUE",
                    help="a warpgym.sim.physics.Physics setting, e.g. solver_iterations=4 (default: the task's)")
    ap.add_argument("--njmax", type=positive_int(128), nargs="+", default=[None],
                    help="constraint rows per world to compare (default: each robot's, warpgym/sim/robots.py)")
    ap.add_argument("--no-mathdx", action="store_true",
                    help="compile Warp's tile Cholesky without libmathdx (faster to compile; see the timings)")
    ap.add_argument("--out", default=None, help="JSON file to write (default: print only)")
    return ap


def main(argv=None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    check_device(ap, args.device)
    if args.no_mathdx:
        wp.config.enable_mathdx_solver = False
    try:
        physics = dict(parse_setting(text) for text in args.physics)
        Physics.from_dict(physics)
    except ValueError as e:
        ap.error(f"--physics: {e}")
    from warpgym.tasks.registry import canonical  # noqa: PLC0415

    names = []
    for flag, given in (("--tasks", args.tasks), ("--legged", args.legged)):
        try:
            names += [canonical(name) for name in given or ()]
        except ValueError as e:
            ap.error(f"{flag}: {e}")
    if names and physics:
        ap.error(f"--physics {' '.join(args.physics)}: it sets Ant's and Humanoid's physics under --robots; the "
                 "tasks of --tasks run with their own")
    device = resolve_device(args.device)
    gpu = torch.cuda.get_device_name(torch.device(device)) if device.startswith("cuda") else platform.processor()

    if names:
        return bench_tasks(names, args, device, gpu, argv)
    from warpgym.cli.bench.robots import bench_one  # noqa: PLC0415  (the robots' loops, beside their family's)

    rows = []
    for robot in args.robots:
        for n in args.num_envs:
            for njmax in args.njmax:
                r = bench_one(robot, n, device, args.steps, args.repeats, physics, njmax)
                rows.append(r)
                print(json.dumps(r), flush=True)

    print(f"\n{gpu}, {args.steps} steps x {args.repeats} repeats, median env-steps/s")
    print(f"physics settings: {physics or 'the task defaults'}")
    print("| robot | envs | njmax | MuJoCo Warp | raw Newton | warpgym physics | physics/raw | env (task) | "
          "env/physics | MiB/1k envs |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['robot']} | {r['num_envs']} | {r['njmax']} | {r['mjwarp_steps_per_s'] / 1e6:.2f}M | "
              f"{r['raw_steps_per_s'] / 1e6:.2f}M | "
              f"{r['physics_steps_per_s'] / 1e6:.2f}M | {r['physics_over_raw']:.3f} | "
              f"{r['env_steps_per_s'] / 1e6:.2f}M | {r['env_over_physics']:.3f} | "
              f"{r['gpu_mem_mib'] / r['num_envs'] * 1000:.0f} |")
    save_results(args, device, gpu, argv, rows)
    return 0


def save_results(args, device, gpu, argv, rows) -> None:
    if args.out:
        meta = {"device": device, "gpu": gpu, "warp": wp.__version__, "torch": torch.__version__,
                "mathdx_solver": bool(wp.config.enable_mathdx_solver),
                "command": " ".join([os.path.basename(sys.argv[0])] + (argv if argv is not None else sys.argv[1:]))}
        os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
        write_json(args.out, {"meta": meta, "results": rows, "rows": rows})


def _median(value) -> float:
    return statistics.median(value) if isinstance(value, list) else value


def bench_tasks(names: list[str], args, device, gpu, argv) -> int:
    """Each task's row from its registry entry's ``bench``, then one table of them all."""
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    rows = []
    for name in names:
        for n in args.num_envs:
            for njmax in args.njmax:
                r = task_entry(name).bench(name, n, device, args.steps, args.warmup, args.repeats, njmax)
                rows.append(r)
                print(json.dumps({k: v for k, v in r.items() if not k.endswith("seconds")}), flush=True)
    print(f"\n{gpu}, {args.steps} steps x {args.repeats} repeats, median env-steps/s (MuJoCo Warp: its own step of "
          "the task's worlds, with the forward pass the legged tasks' step ends with)")
    print("| task | envs | njmax | MuJoCo Warp | warpgym env | env/MuJoCo Warp |")
    print("|---|---:|---:|---:|---:|---:|")
    for r in rows:
        env, phys = _median(r["env_steps_per_s"]), _median(r["mjwarp_steps_per_s"])
        print(f"| {r['task']} | {r['num_envs']} | {r.get('njmax') or '-'} | {phys / 1e6:.3f}M | {env / 1e6:.3f}M "
              f"| {env / phys:.3f} |")
    save_results(args, device, gpu, argv, rows)
    return 0

