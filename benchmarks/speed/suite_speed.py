"""Gymnasium's MuJoCo suite, env-steps/s on one GPU beside the CPU simulators users run today on the
same host: warpgym's whole task step and MuJoCo Warp's own step of the file's model at each env
count (``warpgym bench --tasks``), Gymnasium's own envs in ``AsyncVectorEnv`` over the host's cores,
and EnvPool 1.2.7 (C++ threads, the same MuJoCo files) with as many threads as cores.

    python -m benchmarks.speed.suite_speed --out OUT.json                        # all eleven tasks, GPU and CPU
    python -m benchmarks.speed.suite_speed --out A.json --tasks Hopper-v5 --skip-cpu
    python -m benchmarks.speed.suite_speed --report A.json B.json ...            # one table from several runs

Every figure is the median of --repeats timings taken in one run. A run writes its JSON after each
task, so one cut short keeps what it measured; --report refuses runs from different GPUs.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time



def cpu_async(name: str, envs: int, seconds: float, repeats: int) -> dict:
    """Gymnasium's own env, ``envs`` copies in AsyncVectorEnv subprocesses, uniform random actions."""
    import gymnasium as gym  # noqa: PLC0415

    vec = gym.make_vec(name, num_envs=envs, vectorization_mode="async")
    vec.reset(seed=0)
    vec.action_space.seed(0)
    rates = []
    for _ in range(repeats + 1):  # the first is a warm-up
        steps, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            vec.step(vec.action_space.sample())
            steps += 1
        rates.append(envs * steps / (time.perf_counter() - t0))
    vec.close()
    return {"envs": envs, "steps_per_s": statistics.median(rates[1:]), "all": rates[1:]}


def cpu_envpool(name: str, envs: int, threads: int, seconds: float, repeats: int) -> dict:
    """EnvPool's synchronous pool of the same task: ``envs`` worlds on ``threads`` C++ threads."""
    import envpool  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415

    pool = envpool.make_gymnasium(name, num_envs=envs, batch_size=envs, num_threads=threads, seed=0)
    pool.reset()
    space = pool.action_space
    rng = np.random.default_rng(0)
    actions = [rng.uniform(space.low, space.high, (envs,) + space.shape).astype(space.dtype) for _ in range(8)]
    rates = []
    for _ in range(repeats + 1):
        steps, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds:
            pool.step(actions[steps % 8])
            steps += 1
        rates.append(envs * steps / (time.perf_counter() - t0))
    pool.close()
    return {"envs": envs, "threads": threads, "steps_per_s": statistics.median(rates[1:]), "all": rates[1:]}


def best_envpool(name: str, threads: int, seconds: float, repeats: int) -> dict:
    """EnvPool at one env per thread and at four: the faster (more envs hide its batching overhead)."""
    runs = [cpu_envpool(name, threads * k, threads, seconds, repeats) for k in (1, 4)]
    return max(runs, key=lambda r: r["steps_per_s"]) | {"tried": runs}


def table(runs: list[dict]) -> str:
    gpu = {(r["task"], r["num_envs"]): r for run in runs for r in run.get("gpu", [])}
    cpu = {t: c for run in runs for t, c in run.get("cpu", {}).items()}
    tasks = list(dict.fromkeys(t for t, _ in gpu))
    sizes = sorted({n for _, n in gpu})
    head = "| task | " + " | ".join(f"{n // 1024}k envs: warpgym (x MuJoCo Warp)" for n in sizes)
    head += " | Gymnasium async | EnvPool | warpgym best / EnvPool |"
    lines = [head, "|---" * (len(sizes) + 4) + "|"]
    for t in tasks:
        cells, best = [], 0.0
        for n in sizes:
            r = gpu.get((t, n))
            if r is None:
                cells.append("")
                continue
            best = max(best, r["env_steps_per_s"])
            cells.append(f"{r['env_steps_per_s'] / 1e6:.2f} M ({r['env_over_mjwarp']:.2f})")
        c = cpu.get(t, {})
        ga = c.get("gymnasium_async", {}).get("steps_per_s")
        ep = c.get("envpool", {}).get("steps_per_s")
        ratio = f"{best / ep:.0f}x" if ep else "not measured"
        lines.append(f"| {t} | " + " | ".join(cells) + f" | {f'{ga / 1e3:.1f} k' if ga else 'not measured'} | "
                     f"{f'{ep / 1e3:.1f} k' if ep else 'not measured'} | {ratio} |")
    return "\n".join(lines)


def report(paths: list[str]) -> int:
    runs = [json.load(open(p)) for p in paths]
    gpus = {r["meta"]["gpu"] for r in runs}
    if len(gpus) > 1:
        raise SystemExit(f"--report: these runs were made on different GPUs ({sorted(gpus)}); pass runs of one machine")
    meta = runs[0]["meta"]
    print(f"{meta['gpu']}, {meta['cpu_cores']} CPU cores; median of {meta['repeats']} timings; warpgym's whole "
          "task step in env-steps/s, in brackets its share of MuJoCo Warp's own step of the same model")
    print(table(runs))
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="JSON file to write")
    ap.add_argument("--report", nargs="+", metavar="JSON", help="print the table of earlier runs")
    ap.add_argument("--tasks", nargs="+", default=None)
    ap.add_argument("--num-envs", nargs="+", type=int, default=[4096, 8192, 16384, 32768])
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cpu-seconds", type=float, default=4.0, help="seconds per CPU timing")
    ap.add_argument("--skip-cpu", action="store_true")
    ap.add_argument("--skip-gpu", action="store_true")
    args = ap.parse_args(argv)
    if args.report:
        return report(args.report)
    if not args.out:
        ap.error("--out OUT.json is required (or --report JSON...)")
    import torch  # noqa: PLC0415

    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.cli.bench.suite import bench_suite_task  # noqa: PLC0415
    from warpgym.tasks.registry import task_names  # noqa: PLC0415

    tasks = args.tasks or task_names("suite")
    unknown = [t for t in tasks if t not in task_names("suite")]
    if unknown:
        ap.error(f"--tasks {unknown}: choose from {task_names('suite')}")
    device = "cuda:0" if torch.cuda.is_available() else "cpu"
    cores = os.cpu_count() or 1
    meta = {"gpu": torch.cuda.get_device_name(0) if device != "cpu" else "none", "cpu_cores": cores,
            "repeats": args.repeats, "steps": args.steps, "date": time.strftime("%Y-%m-%d"),
            "command": " ".join(["python -m benchmarks.speed.suite_speed"] + (argv if argv is not None else sys.argv[1:]))}
    out = {"meta": meta, "gpu": [], "cpu": {}}

    def save():
        write_json(args.out, out)

    for name in tasks:
        if not args.skip_gpu:
            for n in args.num_envs:
                try:
                    r = bench_suite_task(name, n, device, args.steps, 20, args.repeats)
                except Exception as e:  # one size that does not fit must not cost the rest
                    r = {"task": name, "num_envs": n, "error": repr(e)[:300]}
                out["gpu"].append(r)
                print(json.dumps({k: v for k, v in r.items() if not k.endswith("seconds")}), flush=True)
                save()
        if not args.skip_cpu:
            c = out["cpu"].setdefault(name, {})
            for key, fn in (("gymnasium_async", lambda: cpu_async(name, cores, args.cpu_seconds, args.repeats)),
                            ("envpool", lambda: best_envpool(name, cores, args.cpu_seconds, args.repeats))):
                try:
                    c[key] = fn()
                except Exception as e:
                    c[key] = {"error": repr(e)[:300]}
                print(name, key, json.dumps(c[key])[:300], flush=True)
                save()
    out["gpu"] = [r for r in out["gpu"] if "error" not in r] + [r for r in out["gpu"] if "error" in r]
    save()
    print(table([out]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
