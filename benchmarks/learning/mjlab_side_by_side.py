"""warpgym's legged velocity tasks beside mjlab's own, on the same kind of GPU at the same number of envs.

Two measures, each both frameworks:

- **Bare step**: the env stepped with uniform random actions in [-1, 1], env-steps per second (each repeat 200
  steps after 20, timed between device synchronisations; the median of 3), at 4096 and 8192 envs.
- **Training**: mjlab's own training (``python -m mjlab.scripts.train``: its rl_cfg, rsl_rl 5.4.2) and
  ``warpgym train`` (the task's preset, mjlab's settings), each on a GPU of its own at once, 4096 envs. mjlab's
  training return (rsl_rl's mean over its last 100 episodes) and tracking errors at its 15-minute mark (the mean of
  its rows in the last 30 s before it) are the target; warpgym's time to it is the first row, counted from its
  process's start, whose mean return over 3 consecutive rows reaches mjlab's (both are stochastic-policy training
  episodes of the same reward, 20 s long); warpgym runs several seeds one after another on its GPU.

Runs span several machine calls: ``--start`` measures the bare steps (both at once, each on its own GPU), then
starts the trainings in sessions of their own (they outlive the call); ``--wait SECONDS`` waits for them; ``--report``
writes ``summary.json`` (each run's curve in it) and prints the tables (of several runs at once: a dated row each),
``--figure PNG`` draws the curves. A task needs two GPUs: mjlab on the first, warpgym on the second; with
``--one-gpu`` they take turns on one (the bare steps one after the other, then mjlab's training, then warpgym's
seeds, all in one session of their own; ``--ours-first`` swaps the trainings).
``--pack DIR`` ends any call by writing what the runs have so far into DIR (the logs, metrics and mjlab's event
files as ``runs.tar.gz``; the policies without optimiser state as ``policies.tar.gz``): a machine taken back between
calls then loses only what came after. mjlab's packages for the GPU machine: benchmarks/learning/mjlab_stage.sh.

    python -m benchmarks.learning.mjlab_side_by_side --out OUT --start --tasks Go1VelocityFlat-v0 \\
        --mjlab-python python3 --mjlab-path $HOME/.cache/mjsite
    python -m benchmarks.learning.mjlab_side_by_side --out OUT --wait 560
    python -m benchmarks.learning.mjlab_side_by_side --report OUT
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import shlex
import statistics
import subprocess
import sys
import time

from benchmarks.harness import ROOT, child_env, core_shares, visible_gpus, write_json

MIRRORS = {"Go1VelocityFlat-v0": "Mjlab-Velocity-Flat-Unitree-Go1", "G1VelocityFlat-v0": "Mjlab-Velocity-Flat-Unitree-G1",
           "Go1VelocityRough-v0": "Mjlab-Velocity-Rough-Unitree-Go1",
           "G1VelocityRough-v0": "Mjlab-Velocity-Rough-Unitree-G1"}
MARK = 900.0  # mjlab's 15-minute mark [s]
WINDOW = 30.0  # its rows in the last WINDOW seconds before the mark make its target
SMOOTH = 3  # warpgym's rows a return is averaged over before it is compared
GOAL_SPEED = 5.0  # the issue's goals: 5x mjlab's env-steps/s, its 15-minute quality in a quarter of the time
GOAL_TIME = 0.25
MJLAB_SEED = 42  # mjlab's rl_cfg default
CURVE_EVERY = 5.0  # seconds between the points of a run's curve kept in summary.json


# ---------------------------------------------------------------------------------------------------- jobs
def mjlab_env(args) -> dict:
    """The environment of an mjlab process: its own packages first (MuJoCo and MuJoCo Warp 3.11), warpgym's site
    after them for what they share (Warp), no OpenGL or ffmpeg wanted at import."""
    path = os.pathsep.join(p for p in (ROOT, args.mjlab_path, os.environ.get("PYTHONPATH", "")) if p)
    return {"PYTHONPATH": path, "MUJOCO_GL": "disable", "IMAGEIO_FFMPEG_EXE": "/bin/true", "WANDB_MODE": "disabled"}


def slot(gpu: str, cores: list[int], extra: dict) -> dict:
    return {"env": child_env(CUDA_VISIBLE_DEVICES=gpu, **extra), "preexec_fn": lambda: os.sched_setaffinity(0, cores)}


def assign(tasks: list[str], one_gpu: bool = False) -> list[dict]:
    """mjlab's run of task i on GPU i, warpgym's on GPU len(tasks) + i, each with its GPU's share of the cores; with
    ``one_gpu`` both on the first GPU with all the cores, as they take turns."""
    if one_gpu:
        gpu, cores = visible_gpus(1)[0], core_shares(1)[0]
        return [{"task": t, "mjlab_gpu": gpu, "ours_gpu": gpu, "mjlab_cores": cores, "ours_cores": cores} for t in tasks]
    gpus = visible_gpus(2 * len(tasks))
    shares = core_shares(2 * len(tasks))
    return [{"task": t, "mjlab_gpu": gpus[i], "ours_gpu": gpus[len(tasks) + i], "mjlab_cores": shares[i],
             "ours_cores": shares[len(tasks) + i]} for i, t in enumerate(tasks)]


def speeds(args, plan: list[dict]) -> None:
    """The bare steps of every task, both frameworks, all at once (each process on its own GPU) or, with
    ``--one-gpu``, one after the other."""
    procs = []
    for job in plan:
        t = job["task"]
        sizes = [str(n) for n in args.speed_envs]
        mj = [args.mjlab_python, "-m", "benchmarks.physics.mjlab_side", "speed", os.path.join(args.out, f"speed-mjlab-{t}.json"),
              "--task", t, "--num-envs", *sizes]
        ours = [sys.executable, "-m", "warpgym", "bench", "--legged", t, "--num-envs", *sizes, "--steps", "200",
                "--warmup", "20", "--repeats", "3", "--device", "cuda:0",
                "--out", os.path.join(args.out, f"speed-warpgym-{t}.json")]
        for cmd, gpu, cores, extra, name in ((mj, job["mjlab_gpu"], job["mjlab_cores"], mjlab_env(args), "mjlab"),
                                             (ours, job["ours_gpu"], job["ours_cores"], {}, "warpgym")):
            log = open(os.path.join(args.out, f"speed-{name}-{t}.log"), "w")
            procs.append((cmd, subprocess.Popen(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT,
                                                **slot(gpu, cores, extra))))
            if args.one_gpu:
                procs[-1][1].wait()
    for cmd, p in procs:
        if p.wait() != 0:
            print(f"warning: {' '.join(cmd[:6])} ... exited {p.returncode}; see its log in {args.out}")


def launch(cmd: list[str], log_path: str, gpu: str, cores: list[int], extra: dict) -> subprocess.Popen:
    # a session of its own: the training outlives this call (the machine's next call waits for it)
    with open(log_path, "w") as log:
        return subprocess.Popen(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, start_new_session=True,
                                **slot(gpu, cores, extra))


def start(args) -> None:
    os.makedirs(args.out, exist_ok=True)
    if args.one_gpu and len(args.tasks) > 1:
        raise SystemExit(f"--one-gpu takes one task, not {len(args.tasks)} ({' '.join(args.tasks)}): mjlab's clock "
                         "starts when the call does, so run one task per --out folder")
    plan = assign(args.tasks, args.one_gpu)
    if args.speed_envs:
        speeds(args, plan)
    launched = []
    for job in plan:
        t = job["task"]
        mj_dir = os.path.join(args.out, f"mjlab-{t}")
        mj = ["timeout", "-s", "INT", str(int(args.mjlab_budget + 30)), args.mjlab_python, "-m", "mjlab.scripts.train",
              MIRRORS[t], "--env.scene.num-envs", str(args.num_envs), "--agent.max-iterations", "1000000",
              "--agent.logger", "tensorboard", "--agent.seed", str(args.mjlab_seed), "--log-root", mj_dir]
        seeds = " ".join(str(s) for s in args.seeds)
        ours_cmd = (f"for s in {seeds}; do {sys.executable} -m warpgym train --task {t} --num-envs {args.num_envs} "
                    f"--time-limit {args.ours_budget:g} --seed $s --run-dir {args.out}/warpgym-{t}-seed$s "
                    f"--device cuda:0 --no-plots --save-at {' '.join(str(m) for m in args.save_at)}; done")
        logs = {name: os.path.join(args.out, f"train-{name}-{t}.log") for name in ("mjlab", "warpgym")}
        if args.one_gpu:  # mjlab's training and warpgym's seeds in turn: one shell, mjlab's packages on its command
            mj_env = ["env", *(f"{k}={v}" for k, v in mjlab_env(args).items())]
            # the clock of mjlab's rows starts when its process does, which the shell writes down first
            mj_part = (f"date +%s.%N > {shlex.quote(started_file(args.out, t))}; "
                       f"{shlex.join(mj_env + mj)} > {shlex.quote(logs['mjlab'])} 2>&1")
            ours_part = f"{{ {ours_cmd}; }} > {shlex.quote(logs['warpgym'])} 2>&1"
            chain = f"{ours_part}; {mj_part}" if args.ours_first else f"{mj_part}; {ours_part}"
            started = time.time()
            p = launch(["bash", "-c", chain], os.path.join(args.out, f"train-{t}.log"), job["mjlab_gpu"],
                       job["mjlab_cores"], {})
            launched += [{"task": t, "framework": name, "gpu": job["mjlab_gpu"], "pid": p.pid, "started": started,
                          "command": mj if name == "mjlab" else ours_cmd} for name in ("mjlab", "warpgym")]
            continue
        for name, cmd, gpu, cores, extra in (
                ("mjlab", mj, job["mjlab_gpu"], job["mjlab_cores"], mjlab_env(args)),
                ("warpgym", ["bash", "-c", ours_cmd], job["ours_gpu"], job["ours_cores"], {})):
            started = time.time()
            p = launch(cmd, logs[name], gpu, cores, extra)
            launched.append({"task": t, "framework": name, "gpu": gpu, "pid": p.pid, "started": started,
                             "command": cmd if name == "mjlab" else ours_cmd})
    write_json(os.path.join(args.out, "jobs.json"), {
        "jobs": launched, "num_envs": args.num_envs, "mjlab_budget_s": args.mjlab_budget,
        "ours_budget_s": args.ours_budget, "seeds": args.seeds, "mjlab_seed": args.mjlab_seed,
        "device": gpu_name(), "date": time.strftime("%Y-%m-%d"), "one_gpu": args.one_gpu,
        "ours_first": args.one_gpu and args.ours_first})
    print(f"started {len(launched)} trainings; their logs: {args.out}/train-*.log")


def started_file(out: str, task: str) -> str:
    return os.path.join(out, f"started-mjlab-{task}")


def gpu_name() -> str:
    try:
        out = subprocess.run(["nvidia-smi", "--query-gpu=name", "--format=csv,noheader"], capture_output=True,
                             text=True, timeout=30).stdout.strip().splitlines()
        return out[0] if out else "unknown"
    except (OSError, subprocess.TimeoutExpired):
        return "unknown"


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    # a finished child of this process that nobody waited for is a zombie: it counts as ended
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split()[2] != "Z"
    except OSError:
        return False


def wait(args) -> None:
    with open(os.path.join(args.out, "jobs.json")) as f:
        jobs = json.load(f)["jobs"]
    deadline = time.time() + args.wait
    while time.time() < deadline:
        running = [j for j in jobs if alive(j["pid"])]
        if not running:
            print("every training has ended")
            return
        time.sleep(min(2.0, max(deadline - time.time(), 0.1)))  # a check is a few syscalls: poll often
    print(f"still running: {[(j['framework'], j['task']) for j in jobs if alive(j['pid'])]}")


# ---------------------------------------------------------------------------------------------------- report
def mjlab_scalars(folder: str, started: float) -> list[dict]:
    """The rows of mjlab's TensorBoard log: time since its process started, return, errors, samples/s."""
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator  # noqa: PLC0415

    files = sorted(glob.glob(os.path.join(folder, "**", "events.out.tfevents.*"), recursive=True))
    if not files:
        return []
    acc = EventAccumulator(os.path.dirname(files[-1]), size_guidance={"scalars": 0})
    acc.Reload()
    tags = {"return": "Train/mean_reward", "error_vel_xy": "Metrics/twist/error_vel_xy",
            "error_vel_yaw": "Metrics/twist/error_vel_yaw", "samples_per_s": "Perf/total_fps",
            "length": "Train/mean_episode_length", "terrain_level": "Curriculum/terrain_levels/mean"}
    rows: dict[int, dict] = {}
    for key, tag in tags.items():
        if tag not in acc.Tags()["scalars"]:
            continue
        for e in acc.Scalars(tag):
            row = rows.setdefault(e.step, {"iteration": e.step, "time_s": e.wall_time - started})
            row[key] = e.value
    return [rows[k] for k in sorted(rows)]


def ours_rows(run_dir: str) -> list[dict]:
    path = os.path.join(run_dir, "metrics.jsonl")
    if not os.path.isfile(path):
        return []
    with open(path) as f:
        rows = [json.loads(line) for line in f if line.strip()]
    return [{"iteration": r["iteration"], "time_s": r["time_s"], "return": r.get("return"),
             "error_vel_xy": r.get("episode/error_vel_xy"), "error_vel_yaw": r.get("episode/error_vel_yaw"),
             "samples_per_s": r.get("samples_per_s"), "terrain_level": r.get("curriculum/terrain_level")} for r in rows]


def mean_of(rows: list[dict], key: str) -> float | None:
    values = [r[key] for r in rows if r.get(key) is not None]
    return statistics.fmean(values) if values else None


def at_mark(rows: list[dict], mark: float) -> dict:
    window = [r for r in rows if mark - WINDOW <= r["time_s"] <= mark]
    return {k: mean_of(window, k) for k in ("return", "error_vel_xy", "error_vel_yaw", "terrain_level")} | {"rows": len(window)}


def first_reaching(rows: list[dict], target: float) -> dict | None:
    """The first row whose return, averaged with the SMOOTH - 1 before it, reaches ``target`` (agents.logger's
    first_window, the rule scaling.py's --smooth reads too), with the window's tracking errors and level."""
    from agents.logger import first_window  # noqa: PLC0415

    found = first_window(rows, "return", target, SMOOTH)
    if found is None:
        return None
    window, last = [rows[i] for i in found], rows[found[-1]]
    return {"time_s": last["time_s"], "iteration": last["iteration"], "error_vel_xy": mean_of(window, "error_vel_xy"),
            "error_vel_yaw": mean_of(window, "error_vel_yaw"), "terrain_level": mean_of(window, "terrain_level")}


def curve(rows: list[dict], key: str = "return", every: float = CURVE_EVERY) -> list[list[float]]:
    """``[time_s, value]`` pairs of ``key`` at least ``every`` seconds apart: the figure's line, small enough to
    commit."""
    out: list[list[float]] = []
    for r in rows:
        if r.get(key) is not None and (not out or r["time_s"] - out[-1][0] >= every):
            out.append([round(r["time_s"], 1), round(r[key], 3)])
    return out


def curves(rows: list[dict]) -> dict:
    """The return's curve and, on rough ground, the mean terrain level's (the curriculum's climb)."""
    levels = curve(rows, "terrain_level")
    return {"curve": curve(rows)} | ({"levels": levels} if levels else {})


def median_rate(rows: list[dict]) -> float | None:
    rates = [r["samples_per_s"] for r in rows[len(rows) // 5 :] if r.get("samples_per_s")]
    return statistics.median(rates) if rates else None


def speed_rows(out: str, task: str) -> list[dict]:
    rows = []
    for name in ("mjlab", "warpgym"):
        path = os.path.join(out, f"speed-{name}-{task}.json")
        if os.path.isfile(path):
            with open(path) as f:
                doc = json.load(f)
                ceiling = {r["num_envs"]: statistics.median(r["mjwarp_steps_per_s"])
                           for r in doc.get("results", []) if r.get("mjwarp_steps_per_s")}
                for r in doc["rows"]:
                    rows.append({"framework": name, "num_envs": r["num_envs"],
                                 "env_steps_per_s": statistics.median(r["env_steps_per_s"])}
                                | ({"mjwarp_steps_per_s": ceiling[r["num_envs"]]} if r["num_envs"] in ceiling else {}))
    return rows


def summarize(out: str, mark: float = MARK) -> dict:
    with open(os.path.join(out, "jobs.json")) as f:
        jobs = json.load(f)
    # a jobs.json written before it kept mjlab's seed has none: those runs used mjlab's default
    summary = {"device": jobs["device"], "date": jobs["date"], "num_envs": jobs["num_envs"], "mark_s": mark,
               "mjlab_seed": jobs.get("mjlab_seed", MJLAB_SEED), "tasks": {}}
    for task in sorted({j["task"] for j in jobs["jobs"]}):
        mj_job = next(j for j in jobs["jobs"] if j["task"] == task and j["framework"] == "mjlab")
        started = mj_job["started"]
        if os.path.isfile(started_file(out, task)):  # on one GPU: when its turn came
            with open(started_file(out, task)) as f:
                started = float(f.read())
        mj = mjlab_scalars(os.path.join(out, f"mjlab-{task}"), started)
        entry = {"mirrors": MIRRORS[task], "speed": speed_rows(out, task),
                 "mjlab": {"rows": len(mj), "last_time_s": mj[-1]["time_s"] if mj else None,
                           "samples_per_s_median": median_rate(mj), "at_mark": at_mark(mj, mark)} | curves(mj),
                 "warpgym": []}
        target = entry["mjlab"]["at_mark"]["return"]
        for run_dir in sorted(glob.glob(os.path.join(out, f"warpgym-{task}-seed*"))):
            rows = ours_rows(run_dir)
            seed = int(run_dir.rsplit("seed", 1)[1])
            reached = first_reaching(rows, target) if target is not None else None
            entry["warpgym"].append({"seed": seed, "rows": len(rows), "last_time_s": rows[-1]["time_s"] if rows else None,
                                     "samples_per_s_median": median_rate(rows), "reached": reached,
                                     "at_end": at_mark(rows, rows[-1]["time_s"]) if rows else None}
                                    | curves(rows))
        summary["tasks"][task] = entry
    return summary


def fmt(x, spec=".0f", none="-"):
    return none if x is None else format(x, spec)


def level(d: dict | None) -> str:
    """On rough ground, the mean terrain level beside a return (nothing on flat ground)."""
    x = (d or {}).get("terrain_level")
    return "" if x is None else f" (level {x:.2f})"


def table(*summaries: dict) -> str:
    """One speed table and one training table for the runs of several side-by-side summaries, each row dated. Each
    summary has its own mark: warpgym's time is judged against a quarter of it."""
    devices = sorted({s["device"] for s in summaries})
    envs = sorted({s["num_envs"] for s in summaries})
    lines = [f"{', '.join(devices)}, {', '.join(map(str, envs))} envs for training; the target: mjlab's return at its "
             f"mark, times from each process's start.", "",
             "| task | date | envs | mjlab env-steps/s | warpgym env-steps/s | MuJoCo Warp's steps + forward alone | "
             "warpgym / mjlab (goal 5x) |", "|---|---|---|---|---|---|---|"]
    for summary in summaries:
        for task, e in summary["tasks"].items():
            by = {(r["framework"], r["num_envs"]): r for r in e["speed"]}
            for n in sorted({k[1] for k in by}):
                m = by.get(("mjlab", n), {}).get("env_steps_per_s")
                o = by.get(("warpgym", n), {}).get("env_steps_per_s")
                c = by.get(("warpgym", n), {}).get("mjwarp_steps_per_s")
                ratio = o / m if m and o else None
                met = "" if ratio is None else (", met" if ratio >= GOAL_SPEED else ", not met")
                lines.append(f"| {task} | {summary['date']} | {n} | {fmt(m and m / 1e3)} k | {fmt(o and o / 1e3)} k "
                             f"| {fmt(c and c / 1e3)} k | {fmt(ratio, '.1f')}x{met} |")
    lines += ["", "| task | date | framework | samples/s | return (mjlab: at its mark; warpgym: at its end) | "
              "error xy / yaw then | time to mjlab's return, s (goal: a quarter of the mark) | error xy / yaw there |",
              "|---|---|---|---|---|---|---|---|"]
    for summary in summaries:
        mark = summary.get("mark_s", MARK)
        for task, e in summary["tasks"].items():
            m = e["mjlab"]
            a = m["at_mark"]
            lines.append(f"| {task} | {summary['date']} | mjlab seed {summary.get('mjlab_seed', MJLAB_SEED)} "
                         f"| {fmt(m['samples_per_s_median'] and m['samples_per_s_median'] / 1e3)} k "
                         f"| {fmt(a['return'], '.2f')}{level(a)} "
                         f"| {fmt(a['error_vel_xy'], '.3f')} / {fmt(a['error_vel_yaw'], '.3f')} | {mark:.0f} (the mark) | |")
            for r in e["warpgym"]:
                got = r["reached"]
                when = "not reached" if got is None else f"{got['time_s']:.0f} ({got['time_s'] / mark:.2f}x){level(got)}"
                met = "" if got is None else (" met" if got["time_s"] <= GOAL_TIME * mark else " not met")
                err = "" if got is None else f"{fmt(got['error_vel_xy'], '.3f')} / {fmt(got['error_vel_yaw'], '.3f')}"
                end = r["at_end"] or {}
                lines.append(f"| {task} | {summary['date']} | warpgym seed {r['seed']} "
                             f"| {fmt(r['samples_per_s_median'] and r['samples_per_s_median'] / 1e3)} k "
                             f"| {fmt(end.get('return'), '.2f')}{level(end)} at {fmt(r['last_time_s'])} s "
                             f"| {fmt(end.get('error_vel_xy'), '.3f')} / {fmt(end.get('error_vel_yaw'), '.3f')} "
                             f"| {when}{met} | {err} |")
    return "\n".join(lines)


def draw(summary: dict, path: str) -> None:
    """Return against minutes since each process started, one panel per task: mjlab's run, warpgym's seeds, the
    target (mjlab's return at the mark) dashed, the mark and a quarter of it dotted. On rough ground a second row
    draws the mean terrain level against the same minutes (the curriculum's climb)."""
    import textwrap  # noqa: PLC0415

    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    tasks = list(summary["tasks"])
    mark = summary.get("mark_s", MARK)
    rough = any(e["mjlab"].get("levels") or any(r.get("levels") for r in e["warpgym"])
                for e in summary["tasks"].values())
    panels = [("curve", "training return")] + ([("levels", "mean terrain level")] if rough else [])
    fig, axes = plt.subplots(len(panels), len(tasks), figsize=(5.0 * len(tasks), 3.4 * len(panels)), squeeze=False)
    for col, task in enumerate(tasks):
        e = summary["tasks"][task]
        for row, (key, label) in enumerate(panels):
            ax = axes[row][col]
            if e["mjlab"].get(key):
                ax.plot(*zip(*[(t / 60.0, v) for t, v in e["mjlab"][key]]), color="tab:orange", label="mjlab")
            for i, run in enumerate(e["warpgym"]):
                if run.get(key):
                    ax.plot(*zip(*[(t / 60.0, v) for t, v in run[key]]), color="tab:blue", alpha=0.8,
                            label="warpgym (seeds)" if i == 0 else None)
            target = e["mjlab"]["at_mark"]["return"]
            if key == "curve" and target is not None:
                ax.axhline(target, color="gray", linestyle="--", linewidth=1)
            for x in (mark, GOAL_TIME * mark):
                ax.axvline(x / 60.0, color="gray", linestyle=":", linewidth=1)
            if row == 0:
                ax.set_title(f"{task} ({e['mirrors']})", fontsize=9)
            ax.set_xlabel("minutes since the process started", fontsize=8)
            ax.set_ylabel(label, fontsize=8)
            ax.tick_params(labelsize=7)
            ax.legend(fontsize=7, loc="lower right")
    fig.suptitle(textwrap.fill(f"{summary['device']}, {summary['date']}, {summary['num_envs']} envs; dashed: mjlab's "
                               f"return at {mark / 60.0:.3g} min; dotted: the mark and a quarter of it",
                               width=60 * len(tasks)), fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def pack(out: str, folder: str) -> None:
    """What the runs have so far, in two archives under ``folder``: the runs without ``.pt`` files or warpgym's
    TensorBoard copies, and the policies (each warpgym checkpoint, mjlab's last model) without optimiser state."""
    import tarfile  # noqa: PLC0415

    import torch  # noqa: PLC0415

    from agents.checkpoint import load  # noqa: PLC0415

    os.makedirs(folder, exist_ok=True)
    base = os.path.dirname(os.path.abspath(out))
    with tarfile.open(os.path.join(folder, "runs.tar.gz"), "w:gz") as tar:
        tar.add(out, arcname=os.path.basename(os.path.abspath(out)),
                filter=lambda t: None if t.name.endswith(".pt") or t.name.endswith("/tensorboard") else t)
    with tarfile.open(os.path.join(folder, "policies.tar.gz"), "w:gz") as tar:
        for path in sorted(glob.glob(os.path.join(out, "warpgym-*", "checkpoint*.pt"))):
            try:
                ckpt = load(path, torch.device("cpu"))
            except ValueError:
                continue  # being written: the next pack takes it
            ckpt.pop("optimizer", None)
            tmp = path + ".packed"
            torch.save(ckpt, tmp)
            tar.add(tmp, arcname=os.path.relpath(path, base))
            os.remove(tmp)
        for task_dir in sorted(glob.glob(os.path.join(out, "mjlab-*"))):
            models = sorted(glob.glob(os.path.join(task_dir, "**", "model_*.pt"), recursive=True),
                            key=lambda p: int(p.rsplit("_", 1)[1][:-3]))
            if models:
                try:  # rsl_rl's checkpoint: tensors and plain values, read without running code
                    model = torch.load(models[-1], map_location="cpu", weights_only=True)
                except Exception as e:  # noqa: BLE001  (torch reports a refused file as any of several types)
                    print(f"left out {models[-1]}: not read as tensors and plain values ({e})")
                    continue
                tmp = models[-1] + ".packed"
                torch.save({k: v for k, v in model.items() if "optimizer" not in k}, tmp)
                tar.add(tmp, arcname=os.path.relpath(models[-1], base))
                os.remove(tmp)
    print(f"packed {out} into {folder}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="folder for the runs, logs and JSON")
    ap.add_argument("--start", action="store_true", help="measure the bare steps, then start the trainings")
    ap.add_argument("--wait", type=float, help="wait up to this many seconds for the trainings")
    ap.add_argument("--report", metavar="OUT", nargs="+", help="summarise each run folder OUT into its summary.json "
                    "(or read a summary.json written before) and print the runs' tables, one row each")
    ap.add_argument("--tasks", nargs="+", default=["Go1VelocityFlat-v0"], choices=sorted(MIRRORS))
    ap.add_argument("--one-gpu", action="store_true", help="mjlab and warpgym take turns on one GPU (one task): the "
                    "bare steps one after the other, then mjlab's training, then warpgym's seeds")
    ap.add_argument("--ours-first", action="store_true", help="with --one-gpu: warpgym's seeds before mjlab's "
                    "training (a task new to the GPU shows a failure within minutes, not after mjlab's)")
    ap.add_argument("--num-envs", type=int, default=4096)
    ap.add_argument("--speed-envs", type=int, nargs="*", default=[4096, 8192], help="bare-step sizes ([]: none)")
    ap.add_argument("--mjlab-python", default=sys.executable, help="the interpreter that imports mjlab")
    ap.add_argument("--mjlab-path", default="", help="mjlab's packages, first on its PYTHONPATH")
    ap.add_argument("--mjlab-budget", type=float, default=MARK + 60.0)
    ap.add_argument("--mjlab-seed", type=int, default=MJLAB_SEED, help="mjlab's rl_cfg seed (its default)")
    ap.add_argument("--ours-budget", type=float, default=300.0)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--save-at", type=float, nargs="+", default=[120.0, 225.0, 300.0])
    ap.add_argument("--mark", type=float, default=MARK,
                    help="with --report: the time of mjlab's run whose return is the target (default its 15-minute mark)")
    ap.add_argument("--figure", metavar="PNG", help="with --report: also draw return against time into PNG")
    ap.add_argument("--pack", metavar="DIR", help="at the end, write the runs so far into DIR (a machine call's $OUT)")
    args = ap.parse_args(argv)
    if args.report:
        summaries = []
        for path in args.report:
            if os.path.isfile(path):  # a summary.json written before: its table again, at the mark it was made at
                with open(path) as f:
                    summary = json.load(f)
                if args.mark != MARK and args.mark != summary.get("mark_s", MARK):
                    ap.error(f"--mark {args.mark:g}: {path} was summarised at {summary.get('mark_s', MARK):g} s; "
                             f"give its run folder to judge another mark")
            elif os.path.isdir(path):
                summary = summarize(path, args.mark)
                write_json(os.path.join(path, "summary.json"), summary)
            else:
                ap.error(f"--report {path}: neither a run folder nor a summary.json")
            summaries.append(summary)
        if args.figure and len(summaries) > 1:
            ap.error(f"--figure draws one run's curves; give one --report (got {len(summaries)})")
        print(table(*summaries))
        if args.figure:
            draw(summaries[0], args.figure)
        return 0
    if not args.out:
        ap.error("--out is required (or --report OUT)")
    try:
        if args.start:
            start(args)
        if args.wait:
            wait(args)
    finally:
        if args.pack:
            pack(args.out, args.pack)
    return 0


if __name__ == "__main__":
    sys.exit(main())
