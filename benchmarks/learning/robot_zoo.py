"""Each zoo robot from its file alone to the walking gate: ``warpgym train --robot NAME`` on flat ground with the
defaults (nothing tuned per robot beyond its definition), a checkpoint kept every ``--every`` seconds from the
process start, each scored in native MuJoCo over ``warpgym eval``'s fixed schedule of commands: the time to the
first that tracks within 0.15 m/s (xy) and 0.25 rad/s (yaw) with no falls in ``--episodes`` episodes.

    python -m benchmarks.learning.robot_zoo run --robots a1 aliengo mini_cheetah --out OUT   # trains and scores
    python -m benchmarks.learning.robot_zoo table OUT/robot_zoo.json ...                    # the markdown table

``--together N`` trains N robots at once on the one GPU (the times are then upper bounds: the runs share it); the
scoring runs on the CPU cores, a checkpoint a process. OUT/robot_zoo.json holds every checkpoint's scores.
``--algos ppo sac`` trains each robot with each learner (``warpgym train --algo``), side by side under
``--together``; ``--gate-xy`` tightens the gate (the Go1's is 0.10 m/s).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

GATE = {"error_xy": 0.15, "error_yaw": 0.25, "falls": 0}


def train_command(robot: str, run_dir: str, time_limit: float, every: float, seed: int, num_envs: int | None,
                  algo: str = "ppo") -> list:
    marks = [str(int(t)) for t in range(int(every), int(time_limit) + 1, int(every))]
    return [sys.executable, "-m", "warpgym", "train", "--robot", robot, "--seed", str(seed), "--time-limit",
            str(time_limit), "--save-at", *marks, "--run-dir", run_dir, "--no-plots", "--no-eval",
            *(["--num-envs", str(num_envs)] if num_envs else []), *(["--algo", algo] if algo != "ppo" else [])]


def run_names(args) -> list[tuple[str, str, str]]:
    """(run name, robot, learner) of every run: the robot's name alone where one learner trains them all."""
    return [(robot if len(args.algos) == 1 else f"{robot}-{algo}", robot, algo)
            for robot in args.robots for algo in args.algos]


def train_all(args) -> dict[str, dict]:
    """The robots' runs, ``--together`` at a time; each one's log beside its run."""
    out, waiting, running, done = args.out, run_names(args), {}, {}
    while waiting or running:
        while waiting and len(running) < args.together:
            name, robot, algo = waiting.pop(0)
            run_dir = os.path.join(out, name)
            log = open(os.path.join(out, f"{name}.log"), "w")
            cmd = train_command(robot, run_dir, args.time_limit, args.every, args.seed, args.num_envs, algo)
            running[name] = (subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT), log, run_dir,
                             time.time(), robot, algo)
        time.sleep(2.0)
        for name, (proc, log, run_dir, started, robot, algo) in list(running.items()):
            if proc.poll() is not None:
                log.close()
                done[name] = {"run_dir": run_dir, "rc": proc.returncode, "wall_s": round(time.time() - started, 1),
                              "together": min(args.together, len(args.robots) * len(args.algos)), "robot": robot,
                              "algo": algo}
                del running[name]
    return done


def score(job: tuple[str, str, int]) -> dict:
    """One kept checkpoint over the fixed schedule in native MuJoCo (on the CPU, one thread)."""
    import torch  # noqa: PLC0415

    torch.set_num_threads(1)
    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.native.legged import native_episodes  # noqa: PLC0415
    from warpgym.tasks.legged import trained_legged_task  # noqa: PLC0415

    path, robot, episodes = job
    ckpt = torch.load(path, map_location="cpu", weights_only=False)
    task = trained_legged_task(ckpt["config"]["env_args"])
    spec = ckpt["spec"]
    policy, normalize = policy_from_checkpoint(ckpt, spec["num_obs"], spec["num_actions"], torch.device("cpu"))

    @torch.no_grad()
    def act(obs):
        return policy.act_deterministic(normalize(torch.as_tensor(obs)[None]))[0].numpy()

    t = native_episodes(task, act, episodes)
    return {"robot": robot, "path": path, "error_xy": t.error_xy, "error_yaw": t.error_yaw, "falls": t.falls,
            "episodes": t.episodes}


def passes(row: dict, gate: dict = GATE) -> bool:
    return row["error_xy"] <= gate["error_xy"] and row["error_yaw"] <= gate["error_yaw"] and row["falls"] == 0


def summarize(runs: dict, scores: list[dict], gpu: str, args) -> dict:
    robots = {}
    gate = {**GATE, "error_xy": args.gate_xy, "error_yaw": args.gate_yaw}
    for name, run in runs.items():
        robot = run["robot"]
        summary_path = os.path.join(run["run_dir"], "summary.json")
        summary = json.load(open(summary_path)) if os.path.isfile(summary_path) else {}
        kept = {k["path"]: k for k in summary.get("kept_checkpoints", [])}
        rows = sorted(({**r, "time_s": kept[r["path"]]["time_s"], "samples": kept[r["path"]]["samples"]}
                       for r in scores if r["robot"] == name and r["path"] in kept), key=lambda r: r["time_s"])
        first = next((r for r in rows if passes(r, gate)), None)
        from warpgym.tasks.legged.robot_task import load_robot  # noqa: PLC0415

        definition = load_robot(robot)
        robots[name] = {"name": definition.label, "file": os.path.basename(definition.file), **run,
                         "samples_per_s": summary.get("steady_samples_per_s_median"),
                         "first_iteration_s": summary.get("first_iteration_time_s"),
                         "gate_s": first["time_s"] if first else None, "gate_row": first, "checkpoints": rows,
                         "best": min(rows, key=lambda r: (r["falls"], r["error_xy"] + r["error_yaw"])) if rows else None}
    return {"gpu": gpu, "date": time.strftime("%Y-%m-%d"), "gate": gate, "episodes": args.episodes,
            "time_limit_s": args.time_limit, "every_s": args.every, "seed": args.seed, "together": args.together,
            "command": "python -m benchmarks.learning.robot_zoo run " + " ".join(sys.argv[2:]), "robots": robots}


def table(*runs: dict) -> str:
    """One row per robot and run (a robot run twice, with different company on the GPU, has two)."""
    lines = ["| robot | file | learner | time to the gate | error xy / yaw then [m/s, rad/s] | best in the run (xy / yaw, "
             "falls) | env steps/s (training) | runs sharing the GPU |", "|---|---|---|---|---|---|---|---|"]
    for data in runs:
        for r in data["robots"].values():
            gate, best = r["gate_row"], r["best"]
            when = "%.0f s" % r["gate_s"] if gate else "not within %.0f s" % data["time_limit_s"]
            then = "%.3f / %.3f" % (gate["error_xy"], gate["error_yaw"]) if gate else "-"
            top = ("%.3f / %.3f, %d of %d" % (best["error_xy"], best["error_yaw"], best["falls"], best["episodes"])
                   if best else "-")
            rate = "%.0f k" % (r["samples_per_s"] / 1e3) if r.get("samples_per_s") else "-"
            learner = {"ppo": "PPO", "sac": "SAC"}.get(r.get("algo", "ppo"), r.get("algo"))
            if data["gate"]["error_xy"] != GATE["error_xy"]:
                when += f" (xy <= {data['gate']['error_xy']:g})"
            lines.append(f"| {r['name']} | {r['file']} | {learner} | {when} | {then} | {top} | {rate} | "
                         f"{r['together']} |")
    return "\n".join(lines)


def gpu_name() -> str:
    try:
        return subprocess.run(["nvidia-smi", "--query-gpu=name,driver_version", "--format=csv,noheader"],
                              capture_output=True, text=True, check=True).stdout.strip().splitlines()[0]
    except (OSError, subprocess.CalledProcessError, IndexError):
        return "no GPU"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.learning.robot_zoo")
    sub = ap.add_subparsers(dest="cmd", required=True)
    run = sub.add_parser("run")
    run.add_argument("--robots", nargs="+", required=True)
    run.add_argument("--out", required=True)
    run.add_argument("--time-limit", type=float, default=540.0)
    run.add_argument("--every", type=float, default=30.0)
    run.add_argument("--episodes", type=int, default=30)
    run.add_argument("--seed", type=int, default=0)
    run.add_argument("--together", type=int, default=1)
    run.add_argument("--num-envs", type=int, default=None)
    run.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    run.add_argument("--gifs", action="store_true", help="draw each robot's chosen checkpoint (warpgym play --gif)")
    run.add_argument("--algos", nargs="+", default=["ppo"], choices=("ppo", "sac"))
    run.add_argument("--gate-xy", type=float, default=GATE["error_xy"])
    run.add_argument("--gate-yaw", type=float, default=GATE["error_yaw"])
    tab = sub.add_parser("table")
    tab.add_argument("json", nargs="+")
    args = ap.parse_args(argv)
    if args.cmd == "table":
        print(table(*(json.load(open(p)) for p in args.json)))
        return 0
    os.makedirs(args.out, exist_ok=True)
    runs = train_all(args)
    jobs = []
    for name, r in runs.items():
        summary = os.path.join(r["run_dir"], "summary.json")
        kept = json.load(open(summary)).get("kept_checkpoints", []) if os.path.isfile(summary) else []
        jobs += [(k["path"], name, args.episodes) for k in kept]
    from multiprocessing import get_context  # noqa: PLC0415

    with get_context("spawn").Pool(max(1, min(args.workers, len(jobs) or 1))) as pool:
        scores = pool.map(score, jobs, chunksize=1)
    data = summarize(runs, scores, gpu_name(), args)
    for robot, r in data["robots"].items():  # a clip of the checkpoint that passed (else the best one)
        chosen = r["gate_row"] or r["best"]
        if args.gifs and chosen:
            gif = os.path.join(args.out, f"{robot}.gif")
            with open(os.path.join(args.out, f"{robot}.log"), "a") as log:
                subprocess.run([sys.executable, "-m", "warpgym", "play", chosen["path"], "--gif", gif, "--steps", "300",
                                "--gif-width", "320"], stdout=log, stderr=subprocess.STDOUT, check=False)
            r["gif"] = os.path.basename(gif) if os.path.isfile(gif) else None
    with open(os.path.join(args.out, "robot_zoo.json"), "w") as f:
        json.dump(data, f, indent=1)
    print(table(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
