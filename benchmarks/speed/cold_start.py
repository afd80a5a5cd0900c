"""Time a fresh machine's first training runs: empty Warp kernel cache, then warm, then a copied cache.

    python -m benchmarks.speed.cold_start --out OUT                # the runs of docs/history.md, "Cold start"
    python -m benchmarks.speed.cold_start --out OUT --profile-warm # and a warm start under cProfile
    python -m benchmarks.speed.cold_start --out OUT --env WARPGYM_LTO_PROCESSES=0 -- --no-mathdx
    python -m benchmarks.speed.cold_start --report OUT/cold_start.json

Every run is ``scripts/train.py`` with default settings in its own process; ``WARP_CACHE_PATH``
picks the cache each starts from:

- ``Ant cold``: an empty cache, twice, each time a new one;
- ``Humanoid cold``: an empty cache; ``Humanoid after Ant``: the first Ant run's cache;
- ``Ant warm``: the first Ant run's cache again, twice;
- ``Ant, copied cache``: a copy of that cache in another folder, as a cluster job would get it
  from shared storage (Warp names cached modules by content hash, not by path).

Writes OUT/cold_start.json (each run's start-up timeline and per-module compile record from its
summary.json) and prints the table of docs/benchmarks.md, then the compile timeline of the
second empty-cache Ant run (the first also pays for the machine's cold file cache).
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

from benchmarks.harness import ROOT, read_report, write_json  # noqa: E402

from benchmarks.targets import WALKING  # noqa: E402


def train(out: str, name: str, task: str, cache: str, seconds: float, extra: list[str], env_vars: dict,
          profile: str | None = None) -> dict:
    run_dir = os.path.join(out, name)
    python = [sys.executable] + (["-m", "cProfile", "-o", profile] if profile else [])
    cmd = [*python, os.path.join(ROOT, "scripts", "train.py"), "--task", task, "--time-limit", str(seconds),
           "--run-dir", run_dir, "--no-plots", *extra]
    env = {**os.environ, **env_vars, "WARP_CACHE_PATH": cache, "PYTHONUNBUFFERED": "1"}
    start = time.time()
    with open(os.path.join(out, f"{name}.log"), "w") as log:
        code = subprocess.call(cmd, env=env, stdout=log, stderr=subprocess.STDOUT, cwd=ROOT)
    row = {"name": name, "task": task, "cache": cache, "exit_code": code, "wall_s": round(time.time() - start, 1)}
    path = os.path.join(run_dir, "summary.json")
    if code == 0 and os.path.isfile(path):
        with open(path) as f:
            s = json.load(f)
        row.update({k: s.get(k) for k in ("device", "num_envs", "first_iteration_time_s", "first_train_speed_2ms",
                                          "first_train_speed_3ms", "first_eval_speed_3ms",
                                          "steady_samples_per_s_median", "startup")})
    print(f"{name}: exit {code}, first iteration {row.get('first_iteration_time_s')} s, "
          f"3 m/s at {row.get('first_train_speed_3ms')}", flush=True)
    return row


def cache_size(path: str) -> tuple[int, float]:
    files = [os.path.join(d, f) for d, _, fs in os.walk(path) for f in fs]
    return sum(1 for n in os.listdir(os.path.join(path, os.listdir(path)[0])) if n.startswith("wp_")), \
        sum(os.path.getsize(f) for f in files) / 2**20


def hot_spots(profile: str, count: int = 45) -> list[str]:
    """The functions a profiled run spent most time in (cumulative), as pstats prints them."""
    import io  # noqa: PLC0415
    import pstats  # noqa: PLC0415

    text = io.StringIO()
    pstats.Stats(profile, stream=text).sort_stats("cumulative").print_stats(count)
    return [line for line in text.getvalue().splitlines() if line.strip()]


def measure(args) -> dict:
    os.makedirs(args.out, exist_ok=True)
    root = tempfile.mkdtemp(prefix="warpgym-cold-")
    first = os.path.join(root, "ant-1")
    env_vars = dict(kv.split("=", 1) for kv in args.env)

    def run(name, task, cache, **kw):
        return train(args.out, name, task, cache, args.seconds, args.extra, env_vars, **kw)

    rows = [run("ant_cold_1", "Ant", first)]
    rows.append(run("ant_cold_2", "Ant", os.path.join(root, "ant-2")))
    rows.append(run("humanoid_cold", "Humanoid", os.path.join(root, "humanoid")))
    modules, mib = cache_size(first)
    rows.append(run("humanoid_after_ant", "Humanoid", first))
    copy = os.path.join(root, "copied")
    shutil.copytree(first, copy)
    for i in (1, 2):
        rows.append(run(f"ant_warm_{i}", "Ant", first))
    rows.append(run("ant_copied_cache", "Ant", copy))
    profile = None
    if args.profile_warm:
        path = os.path.join(root, "warm.prof")
        rows.append(run("ant_warm_profiled", "Ant", first, profile=path))
        profile = hot_spots(path) if os.path.isfile(path) else None
    shutil.rmtree(root, ignore_errors=True)
    result = {"command": " ".join(sys.argv), "seconds": args.seconds, "extra": args.extra, "env": env_vars,
              "ant_cache": {"modules": modules, "mib": round(mib, 1)}, "runs": rows, "warm_profile": profile}
    path = os.path.join(args.out, "cold_start.json")
    write_json(path, result)
    return result


def fmt(v, unit=" s") -> str:
    return "-" if v is None else f"{v:.1f}{unit}"


def report(result: dict) -> str:
    lines = ["| run | envs | kernel cache at start | modules compiled | first iteration "
             "| training episodes at walking speed (Ant 3 m/s, Humanoid 2 m/s) |",
             "|---|---:|---|---:|---:|---:|"]
    start_cache = {"ant_cold_1": "empty", "ant_cold_2": "empty", "humanoid_cold": "empty",
                   "humanoid_after_ant": "the Ant's", "ant_warm_1": "warm", "ant_warm_2": "warm",
                   "ant_copied_cache": "the Ant's, copied to another folder", "ant_warm_profiled": "warm (cProfile)"}
    for r in result["runs"]:
        compiled = len((r.get("startup") or {}).get("compiled", [])) if r.get("startup") else None
        reached = (r.get(f"first_train_speed_{WALKING[r['task']]:g}ms") or {}).get("time_s")
        reached = fmt(reached) if reached is not None else f"not within {result['seconds']:g} s"
        envs = r.get("num_envs") or "-"  # train.py's default; runs before 2026-11-25 did not record it
        lines.append(f"| {r['name']} | {envs} | {start_cache.get(r['name'], '?')} | {'-' if compiled is None else compiled} "
                     f"| {fmt(r.get('first_iteration_time_s'))} | {reached} |")
    c = result.get("ant_cache", {})
    lines.append(f"\nThe Ant's cache: {c.get('modules')} modules, {c.get('mib')} MiB.")
    for r in result["runs"]:
        lines.append(f"\n{r['name']}:")
        for t, text in (r.get("startup") or {}).get("timeline", []):
            lines.append(f"    [{t:6.1f} s] {text}")
        lines.append(f"    [{r.get('first_iteration_time_s') or 0:6.1f} s] first iteration logged")
    cold = next((r for r in result["runs"] if r["name"] == "ant_cold_2" and r.get("startup")), None)
    if cold:
        lines += ["", "Compile timeline of ant_cold_2 (seconds after process start; work split of each module):", "",
                  *compile_table(cold["startup"])]
    if result.get("warm_profile"):
        lines += ["", "ant_warm_profiled, cumulative time by function:", "", *result["warm_profile"]]
    return "\n".join(lines)


def compile_table(startup: dict) -> list[str]:
    rows = [r for r in startup.get("compiled", []) if isinstance(r, dict)]
    out = ["| module | start | end | lock wait | code gen. | of it libmathdx | NVRTC | load |",
           "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in sorted(rows, key=lambda r: r["start"]):
        out.append(f"| {r['module'][:60]} (block {r['block_dim']}) | {r['start']:.1f} | {r['start'] + r['seconds']:.1f} "
                   f"| {r['lock_wait_s']:.2f} | {r['codegen_s']:.2f} | {r['lto_s']:.2f} | {r['native_s']:.2f} "
                   f"| {r['load_s']:.2f} |")
    for b in startup.get("lto_builds", []):
        out.append(f"| libmathdx {b['symbol']} (child process{', failed' if b['error'] else ''}) | {b['start']:.1f} "
                   f"| {b['start'] + b['seconds']:.1f} | | | {b['seconds']:.2f} | | |")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="folder for the runs, their logs and cold_start.json")
    ap.add_argument("--seconds", type=float, default=45.0, help="each run's --time-limit")
    ap.add_argument("--report", metavar="JSON", help="print the table of an earlier run's cold_start.json")
    ap.add_argument("--env", action="append", default=[], metavar="NAME=VALUE",
                    help="an environment variable for every run, e.g. WARPGYM_LTO_PROCESSES=0; repeat for more")
    ap.add_argument("--profile-warm", action="store_true",
                    help="one more warm Ant run under cProfile; its hot spots go into the JSON and the report")
    ap.add_argument("extra", nargs="*", help="more train.py flags, after --, e.g. -- --no-mathdx")
    args = ap.parse_args(argv)
    if args.report:
        print(report(read_report(args.report, "the cold_start.json of an earlier run")))
        return 0
    if not args.out:
        ap.error("--out OUT is needed to measure (or --report JSON to print a table)")
    print(report(measure(args)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
