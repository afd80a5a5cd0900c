"""Learners side by side on one machine, the same task, robots, GPUs and wall-clock budget, one run after another in
one script run: warpgym's PPO, RLlib's PPO (the experiment of ElegantRL's Isaac Gym tutorial: RLlib's successor of
DD-PPO on several GPUs) and the learners of the other adapters (rsl_rl, skrl, rl_games, Stable-Baselines3).

    python -m benchmarks.learning.learners --out OUT                                  # warpgym, RLlib; Ant, Humanoid x 1, 2 GPUs
    python -m benchmarks.learning.learners --out OUT --tasks Ant --gpus 1 --learners warpgym rsl_rl skrl rl_games sb3 \
        --seconds 120                                                                 # every adapter, one GPU
    python -m benchmarks.learning.learners --report OUT --figures docs/figures        # table and figures again
    python -m benchmarks.learning.learners --report OUT OUT2                          # two runs' rows together
    python -m benchmarks.learning.learners --report docs/bench/rllib/h200_rllib_vs_warpgym_1gpu.json  # a kept JSON

For each task and GPU count G, one run of each learner:
- warpgym: ``warpgym train`` (G = 1) or ``torchrun --nproc_per_node=G -m warpgym train``: G processes, each
  stepping --num-envs robots and all-reducing every minibatch's gradients (``--multi-gpu grow-batch``, as RLlib's
  DDP learners divide the work: each its own mini-batch; ``--warpgym-multi-gpu split``, ``grow-steps`` or ``grow-kl``
  runs warpgym's other ways with the same robots per GPU);
- rllib: ``warpgym train-with rllib --gpus G``: PPO on RLlib's new API stack, G env runners each stepping
  --num-envs robots in one warpgym vector env, and G learners training one policy with torch DDP (see
  warpgym/cli/rllib_run.py for how they map). ``--rllib-env-runners R`` splits the same robots over R runner
  processes instead, so that RLlib samples on R CPU cores;
- rsl_rl, skrl, rl_games, sb3: ``warpgym train-with NAME`` on one GPU, with the adapter's own defaults.

warpgym and RLlib take the same settings as far as each exposes them: the network (the task's), steps per env
between updates, minibatch size, epochs and learning rate. ``--hparams preset`` uses warpgym's task preset for both
(Ant: 16 steps, 32768-sample minibatches, 4 epochs, 3e-4; Humanoid: 32, 32768, 5, 5e-4); ``--hparams seed`` the
ElegantRL tutorial's stated numbers, a minibatch of 1024 samples and a learning rate of 0.001, with the preset's
steps and epochs (the tutorial's "replay buffer of 4096" is read as 4096 envs per GPU).

During each run the GPUs' utilisation (nvidia-smi) and the machine's CPU use (/proc/stat) are sampled every 2 s.
Writes OUT/comparison.json (after every run) and OUT/<task>_learners_reward_vs_*.png (all of a task's runs on one
pair of axes), and prints a table: steady samples/s (``agents.logger.steady_median``: the first fifth of the
iterations left out), the first iteration's time, when the training episodes first reached the target speed (Ant
3 m/s, Humanoid 2 m/s; benchmarks/targets.py), the last return and speed, and median GPU and CPU use. ``--report``
also reads the learners.json files an earlier version of this script kept (docs/bench/learners/).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import threading
import time

from agents.data_parallel import MODES  # noqa: E402
from benchmarks.harness import ROOT, child_env, visible_gpus  # noqa: E402

from benchmarks.targets import WALKING, walking_row  # noqa: E402
ADAPTERS = {"rsl_rl": "rsl_rl (`RslRlVecEnv`)", "skrl": "skrl (`SkrlVecEnv`)", "rl_games": "rl_games (`RlGamesVecEnv`)",
            "sb3": "Stable-Baselines3 (`Sb3VecEnv`, numpy)"}
LEARNERS = ("warpgym", "rllib", *ADAPTERS)
PRESET = {"Ant": {"horizon_len": 16, "batch_size": 32768, "repeat_times": 4, "learning_rate": 3e-4},
          "Humanoid": {"horizon_len": 32, "batch_size": 32768, "repeat_times": 5, "learning_rate": 5e-4}}
SEED = {"batch_size": 1024, "learning_rate": 1e-3}


def settings(task: str, hparams: str, num_envs: int) -> dict:
    out = {**PRESET[task], **(SEED if hparams == "seed" else {})}
    out["batch_size"] = min(out["batch_size"], num_envs * out["horizon_len"])  # no larger than one rollout
    return out


def command(learner: str, task: str, gpus: int, args, run_dir: str) -> list[str]:
    common = ["--task", task, "--time-limit", str(args.seconds), "--seed", str(args.seed), "--run-dir", run_dir,
              "--no-plots", *(["--device", args.device] if args.device else [])]
    if learner in ADAPTERS:  # the adapter's own settings: train-with takes the hyperparameters for rllib only
        return [sys.executable, "-m", "warpgym", "train-with", learner, "--num-envs", str(args.num_envs),
                "--iterations", "1000000", *common]
    common += [f"--{k.replace('_', '-')}={v}" for k, v in settings(task, args.hparams, args.num_envs).items()]
    if learner == "rllib":
        runners = args.rllib_env_runners
        spread = ["--env-runners", str(runners), "--num-envs", str(args.num_envs * gpus // runners)] if runners else \
            ["--num-envs", str(args.num_envs)]  # the same robots per GPU, split over the runners
        return [sys.executable, "-m", "warpgym", "train-with", "rllib", "--gpus", str(gpus), "--iterations", "1000000",
                *spread, *common]
    total = args.num_envs * gpus if args.warpgym_multi_gpu == "split" else args.num_envs  # split: the run's total
    train = ["-m", "warpgym", "train", "--num-envs", str(total), *common, "--max-iterations", "1000000", "--no-eval"]
    if gpus == 1:
        return [sys.executable, *train]
    train += ["--multi-gpu", args.warpgym_multi_gpu]
    return [sys.executable, "-m", "torch.distributed.run", "--standalone", f"--nproc_per_node={gpus}", *train]


class Usage:
    """GPU utilisation of the GPUs ``ids`` (nvidia-smi's indices) and the host's CPU use, sampled every ``every``
    seconds in a thread while a run lasts."""

    def __init__(self, ids: list[str], every: float = 2.0):
        self.ids, self.every = ids, every
        self.gpu: list[float] = []
        self.cpu: list[float] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, daemon=True)

    @staticmethod
    def _cpu_times() -> tuple[int, int]:
        with open("/proc/stat") as f:
            values = [int(v) for v in f.readline().split()[1:]]
        return sum(values), values[3] + values[4]  # all, idle + iowait

    def _loop(self) -> None:
        total, idle = self._cpu_times()
        while not self._stop.wait(self.every):
            t, i = self._cpu_times()
            if t > total:
                self.cpu.append(100.0 * (1 - (i - idle) / (t - total)))
            total, idle = t, i
            try:
                out = subprocess.run(["nvidia-smi", "-i", ",".join(self.ids), "--query-gpu=utilization.gpu",
                                      "--format=csv,noheader,nounits"], capture_output=True, text=True, timeout=10).stdout
                self.gpu.append(statistics.mean(float(v) for v in out.split()))
            except (OSError, ValueError, subprocess.TimeoutExpired, statistics.StatisticsError):
                pass

    def __enter__(self):
        self._thread.start()
        return self

    def __exit__(self, *exc):
        self._stop.set()
        self._thread.join()

    def summary(self) -> dict:
        med = (lambda v: round(statistics.median(v), 1) if v else None)  # noqa: E731
        return {"gpu_util_pct": med(self.gpu), "cpu_use_pct": med(self.cpu), "cpu_cores": os.cpu_count()}


def row_of(task: str, learner: str, gpus: int, run_dir: str, wall_s: float, rc: int, usage: dict) -> dict:
    return {"task": task, "learner": learner, "gpus": gpus, "run_dir": run_dir, "rc": rc, "wall_s": round(wall_s, 1),
            **usage, **walking_row(run_dir, task)}


def label(r: dict) -> str:
    """"warpgym PPO, 1 GPU", "RLlib PPO, 2 GPUs", "RLlib PPO, 1 GPU, 8 env runners", "skrl (`SkrlVecEnv`), 1 GPU"."""
    runners = f", {r['env_runners']} env runners" if r.get("env_runners") else ""
    name = ADAPTERS.get(r["learner"]) or f"{'warpgym' if r['learner'] == 'warpgym' else 'RLlib'} PPO"
    return f"{name}, {r['gpus']} GPU{'s' if r['gpus'] > 1 else ''}{runners}"


def of_cores(r: dict) -> str:
    """' of 64' where the row records its host's cores (older rows do not): a share of 16 cores and of 64 differ."""
    return f" of {r['cpu_cores']}" if r.get("cpu_cores") and r.get("cpu_use_pct") is not None else ""


def table(doc: dict) -> str:
    def fmt(v, spec, unit=""):
        return "-" if v is None else format(v, spec) + unit

    runs = f", rows of {doc['script_runs']} script runs ({', '.join(doc['dates'])})" if doc.get("script_runs") else ""
    lines = [f"{doc['device']}, {doc['num_envs']} envs per GPU, {doc['seconds']:g} s per run, hparams {doc['hparams']}{runs}",
             "", "| task | learner | samples/s | first iteration | training episodes at target speed | last return "
             "| last speed | GPU use | CPU use |", "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in doc["rows"]:
        hit = ("not within the run" if r.get("time_to_target_s") is None else
               f"{WALKING[r['task']]:g} m/s at {r['time_to_target_s']:.0f} s ({r['samples_to_target'] / 1e6:.1f} M)")
        sps = r.get("samples_per_s")
        first = r.get("first_row_s", r.get("first_iteration_s"))  # the kept files of 2026-11-24 name it so
        lines.append(f"| {r['task']} | {label(r)} | "
                     f"{fmt(None if sps is None else sps / 1e6, '.3f', ' M')} | {fmt(first, '.0f', ' s')} | {hit} | {fmt(r.get('final_return'), '.0f')} | "
                     f"{fmt(r.get('final_speed'), '.2f', ' m/s')} | {fmt(r.get('gpu_util_pct'), '.0f', ' %')} | "
                     f"{fmt(r.get('cpu_use_pct'), '.0f', ' %')}{of_cores(r)} |")
    return "\n".join(lines)


def figures(doc: dict, out_dir: str) -> list[str]:
    from agents.plotting import plot_runs

    written = []
    for task in dict.fromkeys(r["task"] for r in doc["rows"]):
        runs = [r for r in doc["rows"] if r["task"] == task and r.get("iterations")
                and os.path.isfile(os.path.join(r["run_dir"], "metrics.jsonl"))]  # a kept JSON may have no runs
        if not runs:
            continue
        paths = plot_runs([r["run_dir"] for r in runs], out_dir, labels=[label(r) for r in runs],
                          title=f"warpgym {task}: learners side by side ({doc['device']})")
        for p in paths:
            dest = os.path.join(out_dir, f"{task.lower()}_learners_{os.path.basename(p)}")
            os.replace(p, dest)
            written.append(dest)
    return written


ALIKE = ("device", "num_envs", "seconds", "hparams")  # what makes rows of two runs comparable, with each task's settings


def as_comparison(part: dict) -> dict:
    """A learners.json of this script's earlier version (one task, one GPU, the adapters' defaults) in
    comparison.json's form."""
    if "settings" in part:
        return part
    rows = [{"task": part["task"], "gpus": 1, **r} for r in part["rows"]]
    return {"device": part["device"], "date": part["date"], "num_envs": part["num_envs"], "seconds": part["seconds"],
            "hparams": "the adapters' defaults (warpgym: its preset)", "settings": {}, "rows": rows}


def merged_reports(outs: list[str]) -> dict:
    """The comparison.json of each earlier OUT (or a comparison JSON kept under another name), rows in order, each
    row's run directory found beside its JSON wherever it was copied to; a ValueError names an OUT that is missing
    or was run differently (a task both ran with other settings)."""
    doc = None
    for out in outs:
        path = out if os.path.isfile(out) else os.path.join(out, "comparison.json")
        if not os.path.isfile(path):
            raise ValueError(f"--report {out}: no comparison.json there; pass an --out directory of an earlier run "
                             "or its comparison JSON")
        with open(path) as f:
            part = as_comparison(json.load(f))
        for r in part["rows"]:
            r["run_dir"] = os.path.join(os.path.dirname(path), os.path.basename(r["run_dir"]))
        if doc is None:
            doc = part
            continue
        differ = [k for k in ALIKE if part.get(k) != doc.get(k)]
        differ += [f"{t}'s settings" for t in part["settings"] if doc["settings"].get(t, part["settings"][t]) !=
                   part["settings"][t]]
        if differ:
            raise ValueError(f"--report {out}: its runs differ from {outs[0]}'s in {', '.join(differ)}; "
                             "report runs made alike together, the others apart")
        doc["settings"] = {**doc["settings"], **part["settings"]}
        doc["rows"] += part["rows"]
        doc["script_runs"] = doc.get("script_runs", 1) + 1
        doc["dates"] = sorted(set(doc.get("dates", [doc["date"]])) | {part["date"]})
    tasks = list(dict.fromkeys(r["task"] for r in doc["rows"]))
    doc["rows"].sort(key=lambda r: tasks.index(r["task"]))  # a task's rows together, each run's in its order
    return doc


def save(out: str, doc: dict) -> None:
    from warpgym.cli import write_json

    write_json(os.path.join(out, "comparison.json"), doc)


def run(args) -> int:
    import torch

    os.makedirs(args.out, exist_ok=True)
    device = torch.cuda.get_device_name(0) if torch.cuda.is_available() and args.device != "cpu" else "cpu"
    doc = {"device": device, "date": time.strftime("%Y-%m-%d"), "num_envs": args.num_envs, "seconds": args.seconds,
           "warpgym_multi_gpu": args.warpgym_multi_gpu,
           "hparams": args.hparams, "settings": {t: settings(t, args.hparams, args.num_envs) for t in args.tasks}, "rows": []}
    for task in args.tasks:
        for gpus in args.gpus:
            for learner in args.learners:
                run_dir = os.path.join(args.out, f"{task}-{learner}-{gpus}gpu")
                env = child_env(PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]))
                ids = visible_gpus(gpus)  # the first G of CUDA_VISIBLE_DEVICES: two such runs can share a host
                if device != "cpu":
                    env.update(CUDA_VISIBLE_DEVICES=",".join(ids), CUDA_DEVICE_ORDER="PCI_BUS_ID")  # nvidia-smi's ids
                t0 = time.time()
                with open(run_dir + ".log", "w") as log, Usage(ids) as usage:
                    rc = subprocess.run(command(learner, task, gpus, args, run_dir), stdout=log, stderr=subprocess.STDOUT,
                                        env=env, timeout=args.seconds + 900, check=False).returncode
                doc["rows"].append(row_of(task, learner, gpus, run_dir, time.time() - t0, rc, usage.summary()))
                doc["rows"][-1]["gpu_ids"] = ids
                if learner == "rllib" and args.rllib_env_runners:
                    doc["rows"][-1]["env_runners"] = args.rllib_env_runners
                print(json.dumps(doc["rows"][-1]), flush=True)
                save(args.out, doc)
    print(table(doc))
    figures(doc, args.out)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="directory for the runs, comparison.json and the figures")
    ap.add_argument("--tasks", nargs="+", default=["Ant", "Humanoid"], choices=["Ant", "Humanoid"])
    ap.add_argument("--gpus", type=int, nargs="+", default=[1, 2], help="GPU counts to run (default 1 2)")
    ap.add_argument("--learners", nargs="+", default=["warpgym", "rllib"], choices=LEARNERS,
                    help="warpgym, rllib, or an adapter's learner (rsl_rl, skrl, rl_games, sb3: one GPU)")
    ap.add_argument("--num-envs", type=int, default=4096, help="robots per GPU (per env runner for RLlib)")
    ap.add_argument("--warpgym-multi-gpu", choices=MODES, default="grow-batch",
                    help="warpgym's --multi-gpu on several GPUs, each GPU stepping --num-envs robots (default "
                         "grow-batch: each GPU's own mini-batch, as RLlib's DDP learners)")
    ap.add_argument("--seconds", type=float, default=240.0, help="wall-clock budget per run, from process start")
    ap.add_argument("--hparams", choices=["preset", "seed"], default="preset")
    ap.add_argument("--rllib-env-runners", type=int, default=None, metavar="R",
                    help="RLlib: R env runner processes sharing the run's robots (--num-envs x GPUs), for the CPU "
                         "cores RLlib samples with (default: one runner per GPU, in the driver on one GPU)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--device", default=None, help="cpu to run on the CPU (a check of the script, not a figure)")
    ap.add_argument("--report", metavar="OUT", nargs="+",
                    help="print the table of earlier OUTs or their comparison JSONs (one, or several run alike, their "
                         "rows together) and draw the figures again where the runs' metrics are beside them")
    ap.add_argument("--figures", default=None, help="with --report: where the figures go (default: the first OUT)")
    args = ap.parse_args(argv)
    if args.report:
        try:
            doc = merged_reports(args.report)
        except ValueError as e:
            ap.error(str(e))
        print(table(doc))
        first = args.report[0]
        figures(doc, args.figures or (first if os.path.isdir(first) else os.path.dirname(first)))
        return 0
    if not args.out:
        ap.error("--out is required (or --report)")
    if any(g < 1 for g in args.gpus):
        ap.error(f"--gpus {' '.join(map(str, args.gpus))}: each is a number of GPUs, 1 or more")
    if args.num_envs < 1 or not args.seconds > 0:
        ap.error(f"--num-envs {args.num_envs} and --seconds {args.seconds:g}: both must be positive")
    alone = [x for x in args.learners if x in ADAPTERS]
    if alone and any(g > 1 for g in args.gpus):
        ap.error(f"--learners {' '.join(alone)} with --gpus {' '.join(map(str, args.gpus))}: these adapters train on "
                 "one GPU; run them with --gpus 1")
    runners = args.rllib_env_runners
    if runners is not None and any(g > 1 for g in args.gpus):
        ap.error(f"--rllib-env-runners {runners} with --gpus {' '.join(map(str, args.gpus))}: on several GPUs RLlib "
                 "takes one env runner per GPU (warpgym train-with rllib --gpus G); give --rllib-env-runners with "
                 "--gpus 1 only")
    if runners is not None and (runners < 1 or any(args.num_envs * g % runners for g in args.gpus)):
        ap.error(f"--rllib-env-runners {runners}: must be 1 or more and divide the robots of every run "
                 f"(--num-envs {args.num_envs} x --gpus {' '.join(map(str, args.gpus))})")
    return run(args)


if __name__ == "__main__":
    sys.exit(main())
