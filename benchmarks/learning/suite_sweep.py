"""A sweep of PPO settings for one of Gymnasium's MuJoCo tasks: the evidence behind its preset.

Every combination of the grid trains for --seconds with each seed (``warpgym train --config ...``),
and its final policy is scored by ``warpgym eval`` in ``gymnasium.make``'s env: 10 episodes from each of
the reset seeds 0, 1 and 2 by default, as the learning table scores (where episodes end by falls, 5 do not
rank two settings). The table ranks the combinations by that return (mean over seeds), beside each seed's minutes
to the task's published figure by its own evaluations (the learning table's measure) and the training's
throughput; the best row is the candidate preset for warpgym/tasks/presets.py.

    python -m benchmarks.learning.suite_sweep --out OUT --task Hopper-v5 --seconds 120 \\
        --grid num_envs=4096,8192 --grid horizon_len=16,32 --grid gamma=0.99,0.995
    python -m benchmarks.learning.suite_sweep --report OUT/sweep-Hopper-v5.json
    python -m benchmarks.learning.suite_sweep --out OUT --task InvertedPendulum-v5 --seconds 180 --seeds 0 1 2 3 \
        --grid normalize_obs=true,false --gpus 4          # 8 runs, 4 at once
    python -m benchmarks.learning.suite_sweep --report GPU0/sweep-Hopper-v5.json GPU1/sweep-Hopper-v5.json  # one table
    python -m benchmarks.learning.suite_sweep --score OUT/sweep-Hopper-v5.json   # score again, e.g. on a CPU after a GPU
    python -m benchmarks.learning.suite_sweep --times OUT/sweep-Hopper-v5.json   # the minutes, from runs/ beside it

On a host of several GPUs, ``--gpus N`` runs every setting and seed as its own process, N at a time, one per
GPU, each pinned to its share of the cores (what a one-GPU machine with that many cores gives), and joins
them into one sweep-<task>.json. A grid can also be split by hand (one sweep per GPU or machine, each given
part of the grid or of the seeds); ``--report`` joins them, one row per setting, refusing sweeps of another
task, budget, GPU or scoring, and settings left with different seeds. A short run of the task fills Warp's
kernel cache first (``--no-warm-up``: none), so that no combination's budget pays for compiling. ``--score``
plays each final policy again (its runs/ folder beside the JSON) and rewrites the JSON, keeping the earlier
score beside the new.

A machine call shorter than the sweep (10-minute calls) stops it with SIGTERM: each run saves its iteration, and
the same command in the next call keeps what is done (the settings in the JSON; under ``--gpus``, the parts with a
sweep) and goes on with the stopped runs (``warpgym train --resume``, their clocks carrying on).

Grid names: ``num_envs`` (the command's --num-envs) and any ``Config`` field ``warpgym train --config``
takes (learning_rate, gamma, net_dims as 256x128, reward_scale, normalize_obs, ...).
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import shutil
import subprocess
import sys
import threading
import time

from benchmarks.harness import ROOT, read_summary, train_in_parts, waits_out_sigterm  # noqa: E402
from benchmarks.targets import REFERENCE  # noqa: E402

# what a sweep's JSON says of Warp's kernel cache at its first run: filled by the sweep's own warm-up, or as the
# machine had it (--no-warm-up: empty on a fresh machine, warm after another sweep of the task; the runs' train.log
# says which)
KERNEL_CACHE = {False: "warm", True: "as found (--no-warm-up; each run's train.log says)"}


def parse_grid(texts: list[str]) -> dict[str, list[str]]:
    """``["gamma=0.99,0.995", "net_dims=256x128"]`` -> {"gamma": ["0.99", "0.995"], "net_dims": ["256,128"]}"""
    grid = {}
    for text in texts:
        if "=" not in text:
            raise ValueError(f"--grid {text!r}: write NAME=V1,V2,..., e.g. --grid gamma=0.99,0.995")
        name, values = (s.strip() for s in text.split("=", 1))
        items = [v.strip().replace("x", ",") for v in values.split(",") if v.strip()]
        if not items:
            raise ValueError(f"--grid {text!r}: no values")
        grid[name] = items
    return grid


def command(task: str, combo: dict, seed: int, seconds: float) -> list[str]:
    """``warpgym train``'s flags for one setting and seed (train_in_parts adds the run folder and the device)."""
    cmd = ["--task", task, "--seed", str(seed), "--time-limit", str(seconds)]
    for name, value in combo.items():
        cmd += ["--num-envs", value] if name == "num_envs" else ["--config", f"{name}={value}"]
    return cmd


def run_name(task: str, label: str, seed: int) -> str:
    """A run's folder name, the same in every call (a run stopped by a call's limit goes on under it): the
    learning table's form (suite_learning.run_stem), with the setting's label ("preset" for none)."""
    from benchmarks.learning.suite_learning import run_stem  # noqa: PLC0415

    return run_stem(task, seed, (label,))


def score(run_dir: str, scoring: dict, device: str | None) -> dict:
    """The final policy of ``run_dir`` scored by ``warpgym eval``: episodes from each of the reset seeds in
    Gymnasium's env and from the same starts in warpgym's."""
    from benchmarks.learning.suite_learning import play  # noqa: PLC0415

    result = play(run_dir, scoring["episodes"], scoring["seeds"], os.path.join(run_dir, "eval.json"), device)
    return {"gymnasium_return": result["gymnasium_return"], "ratio": result["gymnasium_over_warpgym"],
            "gymnasium_length": result.get("gymnasium_length")}


def mean_return(runs: list[dict]) -> float | None:
    good = [r for r in runs if "error" not in r]
    return sum(r["gymnasium_return"] for r in good) / len(good) if good else None


def label_of(combo: dict) -> str:
    return " ".join(f"{k}={v}" for k, v in combo.items()) or "preset"


def earlier_rows(path: str, meta: dict) -> dict[str, dict]:
    """The rows an earlier call of the same sweep (task, budget, seeds, scoring) wrote to ``path``, by label."""
    if not os.path.exists(path):
        return {}
    with open(path) as f:
        doc = json.load(f)
    same = ("task", "seconds", "seeds", "scoring")
    if any(doc["meta"].get(k) != meta[k] for k in same):
        raise SystemExit(f"{path} holds a sweep with other {', '.join(same)}: give this one another --out")
    return {r["label"]: r for r in doc["rows"]}


def run_combo(task: str, combo: dict, seeds: list[int], seconds: float, out: str, device: str | None,
              scoring: dict) -> dict:
    label = label_of(combo)
    runs = []
    for seed in seeds:
        run_dir = os.path.join(out, "runs", run_name(task, label, seed))
        # stopped by a call's time limit, the run saves and this exits; the next call's sweep goes on with it
        code = train_in_parts(command(task, combo, seed, seconds), run_dir, ["--time-limit", str(seconds)], device)
        if code != 0:
            runs.append({"seed": seed, "error": f"exit {code}: {run_dir}/train.log"})
            continue
        summary = read_summary(run_dir)
        runs.append({"seed": seed, "run_dir": run_dir, **score(run_dir, scoring, device),
                     "samples": summary["final"]["samples"], "samples_per_s": summary["steady_samples_per_s_median"],
                     "reaching": reaching_of(run_dir, task)})
    return {"combo": combo, "label": label, "runs": runs, "gymnasium_return": mean_return(runs)}


def reaching_of(run_dir: str, task: str) -> dict:
    """When the run's own evaluations first reached the task's published figure and half of it (None where never),
    as the learning table counts its minutes: the sweep's other measure beside the final policy's return."""
    from agents.logger import read_metrics  # noqa: PLC0415
    from benchmarks.learning.suite_learning import reaching  # noqa: PLC0415

    return reaching(read_metrics(run_dir), REFERENCE.get(task))


def runs_beside(path: str) -> tuple[dict, list[tuple[dict, str]]]:
    """A sweep's JSON, and each of its finished runs with the run's folder on this machine: runs/ beside the JSON,
    as the sweep wrote them (on another machine, the JSON's paths are that machine's)."""
    with open(path) as f:
        doc = json.load(f)
    runs_dir = os.path.join(os.path.dirname(os.path.abspath(path)), "runs")
    return doc, [(run, os.path.join(runs_dir, os.path.basename(run["run_dir"])))
                 for row in doc["rows"] for run in row["runs"] if "error" not in run]


def add_times(path: str) -> dict:
    """A sweep's JSON with each run's ``reaching`` taken from its folder's metrics (runs/ beside the JSON), for
    sweeps written before the sweep recorded it or whose policies did not come back (no checkpoint is read)."""
    doc, runs = runs_beside(path)
    for run, here in runs:
        try:
            run["reaching"] = reaching_of(here, doc["meta"]["task"])
        except FileNotFoundError:
            raise SystemExit(f"--times {path}: {here} has no metrics.jsonl; copy the sweep's runs/ folder "
                             "beside its JSON") from None
    return doc


def score_again(path: str, scoring: dict, device: str | None) -> dict:
    """A sweep's JSON with every final policy scored again with ``scoring`` (on this machine: the runs' folders
    sit beside the JSON, under runs/, as the sweep wrote them); the earlier score stays as ``first_score``."""
    doc, runs = runs_beside(path)
    for run, here in runs:
        if not os.path.exists(os.path.join(here, "checkpoint.pt")):
            raise SystemExit(f"--score {path}: {here}/checkpoint.pt is missing; copy the sweep's runs/ folder "
                             "beside its JSON")
        # scored again twice, the first score is still the one the sweep's machine gave
        first = run.get("first_score") or {**{k: run[k] for k in ("gymnasium_return", "ratio")},
                                           **scoring_of(doc["meta"])}
        run.update(score(here, scoring, device), first_score=first, reaching=reaching_of(here, doc["meta"]["task"]))
    for row in doc["rows"]:
        row["gymnasium_return"] = mean_return(row["runs"])
    doc["meta"]["scoring"] = scoring
    return doc


def scoring_of(meta: dict) -> dict:
    """How a sweep's policies were scored; sweeps written before the field scored 5 episodes from seed 0."""
    return meta.get("scoring", {"episodes": 5, "seeds": [0]})


def minutes(run: dict) -> str:
    """A run's minutes to the figure, to the hundredth: sweeps evaluate every 20 s and are read against a line
    at 3 minutes, where one decimal showed a pass at 180.5 s as 3.0 (3.01 here) and one at 178.8 s alike."""
    hit = (run.get("reaching") or {}).get("target")
    return "failed" if "error" in run else f"{hit['time_s'] / 60:.2f}" if hit else "not reached"


def table(doc: dict) -> str:
    rows = sorted(doc["rows"], key=lambda r: -(r["gymnasium_return"] if r["gymnasium_return"] is not None else -1e30))
    # minutes to the published figure, for sweeps that recorded them (2026-11-27 on, or --times)
    timed = any("reaching" in x for r in rows for x in r["runs"])
    figure = REFERENCE.get(doc.get("meta", {}).get("task"))
    to = f" minutes to {figure} (each seed) |" if timed else ""
    # samples/s is the steady iterations' median, which leaves synchronous evaluations out and counts those run
    # beside training (eval_background) in: where the minutes are compared, the samples of the whole budget are
    # shown beside it, evaluations and start included
    seconds = doc.get("meta", {}).get("seconds")
    budget = (f" samples in {seconds:g} s |" if seconds else " samples in the budget |") if timed else ""
    lines = ["| rank | settings | Gymnasium's env: return (mean of seeds) | per seed |" + to + " episode length | "
             "samples/s |" + budget + " lowest ratio |",
             "|---:|---|---:|---|" + ("---|" if timed else "") + "---:|---:|" + ("---:|" if timed else "") + "---:|"]
    for i, r in enumerate(rows, 1):
        good = [x for x in r["runs"] if "error" not in x]
        ret = f"{r['gymnasium_return']:.1f}" if r["gymnasium_return"] is not None else "failed"
        seeds = ", ".join(f"{x['gymnasium_return']:.0f}" if "error" not in x else "failed" for x in r["runs"])
        # episodes cut short by a fall, where a task ends them; sweeps before 2026-11-25's night did not record it
        lengths = [x["gymnasium_length"] for x in good if x.get("gymnasium_length") is not None]
        length = f"{sum(lengths) / len(lengths):.0f}" if lengths else "-"
        sps = f"{sum(x['samples_per_s'] for x in good) / len(good) / 1e6:.2f} M" if good else "-"
        ratio = f"{min(x['ratio'] for x in good):.3f}" if good else "-"
        times = f" {', '.join(minutes(x) for x in r['runs'])} |" if timed else ""
        counted = [x["samples"] for x in good if "samples" in x]  # a run written without it reads "-"
        total = (f" {sum(counted) / len(counted) / 1e6:.1f} M |" if counted else " - |") if timed else ""
        lines.append(f"| {i} | {r['label']} | {ret} | {seeds} |{times} {length} | {sps} |{total} {ratio} |")
    return "\n".join(lines)


def merged(docs: list[dict], failed: list[dict] = ()) -> dict:
    """One sweep of several that ran the same task and budget on the same GPU, scored alike: their rows together.
    A grid split over GPUs by setting adds rows; one split by seed adds runs to a setting's row. Every setting
    must end with the same seeds, each run once, so that the rows' means compare. ``failed``: rows of processes
    that wrote no sweep (``--gpus``), their runs errors that keep the seed's place."""
    keys = ("task", "seconds", "gpu", "scoring")
    kinds = {tuple(json.dumps(d["meta"][k] if k != "scoring" else scoring_of(d["meta"])) for k in keys) for d in docs}
    if len(kinds) > 1:
        raise SystemExit(f"--report: these sweeps differ in {', '.join(keys)} ({sorted(kinds)}); report them apart")
    rows: dict[str, dict] = {}
    for r in [row for d in docs for row in d["rows"]] + list(failed):
        rows.setdefault(r["label"], {**r, "runs": []})["runs"].extend(r["runs"])
    seeds = {label: sorted(x["seed"] for x in r["runs"]) for label, r in rows.items()}
    if len({tuple(s) for s in seeds.values()}) > 1 or any(len(set(s)) < len(s) for s in seeds.values()):
        raise SystemExit(f"--report: the settings ran on different seeds, or a seed twice ({seeds}); join sweeps "
                         "that give every setting the same seeds")
    for r in rows.values():
        r["gymnasium_return"] = mean_return(r["runs"])
    return {"meta": {**docs[0]["meta"], "seeds": next(iter(seeds.values()), docs[0]["meta"]["seeds"]),
                     "dates": sorted({d["meta"]["date"] for d in docs}),
                     "commands": [d["meta"]["command"] for d in docs]},
            "rows": list(rows.values())}


def spread(args, grid: dict[str, list[str]], argv: list[str]) -> dict:
    """``--gpus N``: each setting and seed of the grid its own sweep process, N at a time, one per GPU, each
    pinned to its share of the cores, writing under OUT/parts/<k>; their sweeps joined into one, their runs
    moved to OUT/runs (so that ``--score`` finds them beside the JSON). A process that wrote nothing leaves
    its run as an error row that names its log."""
    from benchmarks.harness import gpu_slot  # noqa: PLC0415
    from benchmarks.learning.suite_learning import without  # noqa: PLC0415

    gpu_slot(0, args.gpus)  # too many GPUs for the cores: said before anything starts
    names = list(grid)
    jobs = [(dict(zip(names, values)), seed) for values in itertools.product(*(grid[n] for n in names))
            for seed in args.seeds]
    rest = without(argv, ("--gpus", "--grid", "--seeds", "--out"))
    # a part an earlier call finished has its sweep; the others run (a stopped one goes on: train_in_parts)
    todo = [(k, job) for k, job in enumerate(jobs)
            if not os.path.exists(os.path.join(args.out, "parts", f"{k:03d}", f"sweep-{args.task}.json"))]
    lock = threading.Lock()

    def command_of(k: int, combo: dict, seed: int) -> list[str]:
        cmd = [sys.executable, "-m", "benchmarks.learning.suite_sweep", *rest,
               "--out", os.path.join(args.out, "parts", f"{k:03d}"),
               "--seeds", str(seed), "--no-warm-up"]
        for name, value in combo.items():  # parse_grid read "256x128" as "256,128"
            cmd += ["--grid", f"{name}={value.replace(',', 'x')}"]
        return cmd

    def worker(gpu: int) -> None:
        slot = gpu_slot(gpu, args.gpus)
        while True:
            with lock:
                if not todo or stopping:
                    return
                k, (combo, seed) = todo.pop(0)
            part = os.path.join(args.out, "parts", f"{k:03d}")
            os.makedirs(part, exist_ok=True)
            with open(os.path.join(part, "sweep.log"), "a") as log:
                subprocess.run(command_of(k, combo, seed), cwd=ROOT, stdout=log, stderr=subprocess.STDOUT,
                               check=False, **slot)

    # A call's `timeout` signals the whole process group: the parts save their runs and end (train_in_parts), and
    # this waits for them, so that the next call never finds a part still writing; then it exits, joining nothing.
    threads = [threading.Thread(target=worker, args=(g,)) for g in range(min(args.gpus, len(todo)))]
    with waits_out_sigterm() as stopping:
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    return join_parts(args.out, args.task, jobs)


def join_parts(out: str, task: str, jobs: list[tuple[dict, int]]) -> dict:
    """The sweeps under OUT/parts/<k> (job k: a setting and a seed) as one; each run's folder moved to
    OUT/runs/<task>-<k>."""
    docs, failed = [], []
    os.makedirs(os.path.join(out, "runs"), exist_ok=True)
    for k, (combo, seed) in enumerate(jobs):
        part = os.path.join(out, "parts", f"{k:03d}")
        path = os.path.join(part, f"sweep-{task}.json")
        if not os.path.exists(path):
            label = label_of(combo)
            error = {"seed": seed, "error": f"the process wrote no sweep: see {part}/sweep.log"}
            failed.append({"combo": combo, "label": label, "runs": [error]})
            continue
        with open(path) as f:
            doc = json.load(f)
        for row in doc["rows"]:
            for run in row["runs"]:
                if "run_dir" in run:
                    moved = os.path.join(out, "runs", f"{task}-{k}")
                    if not os.path.isdir(moved):  # an earlier join (a call that ended) moved it already
                        shutil.move(os.path.join(part, "runs", os.path.basename(run["run_dir"])), moved)
                    run["run_dir"] = moved
        docs.append(doc)
    if not docs:
        raise SystemExit(f"--gpus: no process wrote a sweep; see {out}/parts/*/sweep.log")
    return merged(docs, failed)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="folder for the runs and sweep-<task>.json")
    ap.add_argument("--report", nargs="+", metavar="JSON")
    ap.add_argument("--task")
    ap.add_argument("--grid", action="append", default=[], metavar="NAME=V1,V2")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="training budget of each run")
    ap.add_argument("--eval-episodes", type=int, default=10, help="episodes per reset seed (default 10)")
    ap.add_argument("--eval-seeds", type=int, nargs="+", default=[0, 1, 2], help="reset seeds (default 0 1 2)")
    ap.add_argument("--score", nargs="+", metavar="JSON",
                    help="score the sweeps' final policies again (--eval-episodes, --eval-seeds) and rewrite the JSON")
    ap.add_argument("--times", nargs="+", metavar="JSON",
                    help="add each run's minutes to the task's figure from its metrics (runs/ beside the JSON) and "
                         "rewrite the JSON; for sweeps that did not record them")
    ap.add_argument("--device", default=None)
    ap.add_argument("--no-warm-up", action="store_true",
                    help="no short run to fill the kernel cache first (the first run then compiles on its clock)")
    ap.add_argument("--gpus", type=int, default=1,
                    help="run the settings and seeds N at a time, one process per GPU with an equal share of the cores")
    args = ap.parse_args(argv)
    if args.gpus < 1:
        ap.error(f"--gpus {args.gpus}: the number of GPUs to run on, e.g. --gpus 4")
    if args.eval_episodes < 1 or min(args.eval_seeds) < 0:
        ap.error(f"--eval-episodes {args.eval_episodes} / --eval-seeds {args.eval_seeds}: episodes must be positive "
                 "and seeds non-negative, e.g. --eval-episodes 10 --eval-seeds 0 1 2")
    scoring = {"episodes": args.eval_episodes, "seeds": args.eval_seeds}
    if args.score:
        from warpgym.cli import write_json  # noqa: PLC0415

        for path in args.score:
            write_json(path, score_again(path, scoring, args.device))
        args.report = args.score
    if args.times:
        from warpgym.cli import write_json  # noqa: PLC0415

        for path in args.times:
            write_json(path, add_times(path))
        args.report = args.times
    if args.report:
        docs = []
        for path in args.report:
            with open(path) as f:
                docs.append(json.load(f))
        doc = merged(docs)
        meta = doc["meta"]
        how = scoring_of(meta)
        print(f"{meta['task']}, {meta['seconds']:g} s per run, seeds {meta['seeds']}, {meta['gpu']}, "
              f"{', '.join(meta['dates'])}; each final policy scored on {how['episodes']} episodes from each of "
              f"the reset seeds {how['seeds']}")
        print(table(doc))
        return 0
    if not (args.out and args.task):
        ap.error("--out OUT and --task NAME are required (or --report JSON)")
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.tasks.registry import task_names  # noqa: PLC0415

    if args.task not in task_names("suite"):
        ap.error(f"--task {args.task!r}: choose from {task_names('suite')}")
    if not args.seconds > 0:
        ap.error(f"--seconds {args.seconds}: must be positive, e.g. --seconds 120")
    try:
        grid = parse_grid(args.grid)
    except ValueError as e:
        ap.error(str(e))
    import torch  # noqa: PLC0415

    os.makedirs(os.path.join(args.out, "runs"), exist_ok=True)
    if not args.no_warm_up:  # else the first combination's budget pays for compiling the task's kernels
        from benchmarks.learning.suite_learning import warm_up  # noqa: PLC0415

        warm_up(args.task, args.out, args.device)
    path = os.path.join(args.out, f"sweep-{args.task}.json")
    if args.gpus > 1:
        if torch.cuda.device_count() < args.gpus:
            ap.error(f"--gpus {args.gpus}: this machine shows {torch.cuda.device_count()} GPU(s)")
        doc = spread(args, grid, list(argv if argv is not None else sys.argv[1:]))
        doc["meta"].update(grid=grid, runs_at_once=args.gpus, cores=len(os.sched_getaffinity(0)) // args.gpus,
                           kernel_cache=KERNEL_CACHE[args.no_warm_up],
                           command=" ".join(["python -m benchmarks.learning.suite_sweep"] + (argv or sys.argv[1:])))
        write_json(path, doc)
        print(table(doc))
        return 0
    gpu = torch.cuda.get_device_name(0) if torch.cuda.is_available() and args.device != "cpu" else "cpu"
    doc = {"meta": {"task": args.task, "seconds": args.seconds, "seeds": args.seeds, "grid": grid, "gpu": gpu,
                    "scoring": scoring, "kernel_cache": KERNEL_CACHE[args.no_warm_up],
                    "date": time.strftime("%Y-%m-%d"),
                    "command": " ".join(["python -m benchmarks.learning.suite_sweep"] + (argv or sys.argv[1:]))}, "rows": []}
    names = list(grid)
    done = earlier_rows(path, doc["meta"])
    for values in itertools.product(*(grid[n] for n in names)):
        combo = dict(zip(names, values))
        if label_of(combo) in done:  # an earlier call with this --out swept it
            doc["rows"].append(done[label_of(combo)])
            continue
        doc["rows"].append(run_combo(args.task, combo, args.seeds, args.seconds, args.out, args.device, scoring))
        print(json.dumps(doc["rows"][-1])[:300], flush=True)
        write_json(path, doc)
    print(table(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
