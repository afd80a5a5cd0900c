"""Several GPUs on one host: how much sooner each way of dividing the work reaches a target.

    python -m benchmarks.multi_gpu.scaling --out OUT --task Ant --gpus 1 2 4 --modes split grow-batch --seeds 0 1
    python -m benchmarks.multi_gpu.scaling --out OUT --task Humanoid-v5 --gpus 1 4 --seconds 600
    python -m benchmarks.multi_gpu.scaling --out OUT --task G1VelocityFlat-v0 --gpus 1 2 --targets return=36.55 \
        --smooth 3 --stop 40 --seconds 450 --eval-gap 60 --num-envs 4096   # a training return, as mjlab's is read
    python -m benchmarks.multi_gpu.scaling --report OUT [OUT2 ...]   # the table and figures again, runs joined
    python -m benchmarks.multi_gpu.scaling --report docs/bench/multi_gpu --task Humanoid   # a folder of several tasks

One `warpgym train` per GPU count, mode (``--multi-gpu``, agents/data_parallel.py) and seed, G GPUs under
`torchrun --nproc_per_node=G`, with the same flags; one GPU is every mode's baseline. The jobs share the host
(gpu_jobs.py): each waits for as many free GPUs as it needs and gets their share of the cores, so the 1-GPU
baselines run side by side with each other and with multi-GPU jobs, as busy a host as a 4-GPU run's. A run
evaluates (64 envs, deterministic policy) every --eval-gap seconds and stops at its last target (`train
--target`) or after --seconds. The time to each target (agents.logger.time_to_target) is read two ways:
from the process start (wall-clock, start-up and evaluations included) and the learning time, from the first
iteration with the evaluations left out; the goal's ratio is G GPUs' median learning time over one GPU's. A
target on a training row (``return``: the mean of the episodes that ended in one iteration) is read over the mean of
--smooth rows, so a single lucky row does not end a run: give --stop a little past it.

Writes, as the runs end, OUT/scaling_<task>.json (every run: its times, samples/s, phases, last evaluation)
and at the end OUT/scaling_<task>.md (the table, and each seed's iterations to the last target: what one iteration
learns), OUT/<task>_gpus_<key>_vs_time.png and _vs_samples.png, and
OUT/runs_<task>.tar.gz (each run's metrics.jsonl, summary, config and log; no checkpoints: --keep-checkpoints
keeps each run's last as OUT/checkpoints/<run>.pt). Stopped early (SIGTERM:
a device call's time limit), it stops its jobs and still writes all of these, with the stopped runs' rows as far as
they went (a miss counts as a seed cut short); `--report` reads an output left unpacked (runs_<task>/) the same way.
"""

from __future__ import annotations

import argparse
import glob
import json
import math
import os
import shutil
import signal
import statistics
import sys
import tarfile
import tempfile
import time

from benchmarks.harness import ROOT, TRAIN, read_summary, write_json  # noqa: E402

from benchmarks.multi_gpu.gpu_jobs import Job, run_jobs  # noqa: E402


# the targets; a suite task without one here is timed to Tianshou's (or SLM-Lab's) figure
TARGETS = {"Ant": ("eval/speed", (8.0, 9.5)), "Humanoid": ("eval/speed", (6.0,)),
           "Humanoid-v5": ("eval/return", (10000.0,)), "Ant-v5": ("eval/return", (5850.0,))}


def default_targets(task: str) -> tuple[str, tuple[float, ...]]:
    if task in TARGETS:
        return TARGETS[task]
    from benchmarks.targets import REFERENCE  # noqa: PLC0415

    return "eval/return", (REFERENCE[task],)


def parse_targets(text: str) -> tuple[str, tuple[float, ...]]:
    """``eval/speed=8,9.5`` -> ("eval/speed", (8.0, 9.5))."""
    key, _, values = text.partition("=")
    try:
        numbers = tuple(sorted(float(v) for v in values.split(",")))
    except ValueError:
        numbers = ()
    if not key or not numbers or not all(math.isfinite(v) for v in numbers):
        raise ValueError(f"--targets {text!r}: write KEY=V1,V2 with a logged key, e.g. eval/speed=8,9.5")
    return key, numbers


def preset_mode(task: str) -> str:
    """The --multi-gpu mode `warpgym train` gives the task when none is named: its preset's
    (warpgym.tasks.presets)."""
    from agents.config import Config  # noqa: PLC0415
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    return Config.from_preset(task_entry(task).preset).multi_gpu


def run_name(gpus: int, mode: str, seed: int, label: str = "", repeat: int = 1) -> str:
    """gpu1-seed0, gpu4-split-seed0; with a label (runs made with other flags) gpu1-+16k-seed0, gpu4-split+16k-seed0;
    a seed's second run (--repeat 2: a seed's runs on a GPU are not repeatable bit for bit) gpu1-seed0-r2."""
    setting = ("" if gpus == 1 else mode) + (f"+{label}" if label else "")
    name = f"gpu{gpus}-{setting}-seed{seed}" if setting else f"gpu{gpus}-seed{seed}"
    return name + (f"-r{repeat}" if repeat > 1 else "")


def parse_name(name: str) -> tuple[int, str, int]:
    """run_name's (GPUs, setting, seed); one GPU's setting is "-", or "-+label"."""
    head, _, seed = name.rpartition("-seed")
    gpus, _, setting = head.partition("-")
    return int(gpus[3:]), (setting if not setting.startswith("+") else "-" + setting) or "-", int(seed.split("-r")[0])


def jobs_for(args, runs: str, key: str, stop: float | None) -> list[Job]:
    """The 1-GPU baselines first (one per --baseline-seeds), then each GPU count's modes and seeds; each run stops
    when ``key`` reaches ``stop`` (None: after --seconds)."""
    flags = ["--task", args.task, "--time-limit", str(args.seconds), "--eval-gap", str(args.eval_gap),
             *(["--target", f"{key}={stop:g}"] if stop is not None else []), "--no-plots",
             *(["--num-envs", str(args.num_envs)] if args.num_envs else []),
             *args.train_flags.split()]
    plan = [(1, args.modes[0], s) for s in args.baseline_seeds] if 1 in args.gpus else []
    plan += [(g, m, s) for g in sorted(set(args.gpus) - {1}) for m in args.modes for s in args.seeds]
    jobs = []
    for gpus, mode, seed in plan:
        name = run_name(gpus, mode, seed, args.label, args.repeat)
        d = os.path.join(runs, name)
        # one GPU: `warpgym train`; G GPUs: the same command under torchrun, as the README writes it
        launch = TRAIN if gpus == 1 else [sys.executable, "-m", "torch.distributed.run", "--standalone",
                                          f"--nproc_per_node={gpus}", "-m", *TRAIN[2:]]
        jobs.append(Job(name, gpus, [*launch, *flags, "--seed", str(seed), "--multi-gpu", mode, "--run-dir", d],
                        d + ".log", cwd=ROOT))
    return jobs


def run_row(run_dir: str, key: str, values: tuple[float, ...], smooth: int = 1) -> dict:
    """One run's times to each target, throughput and last evaluation, from its files."""
    from agents.logger import learning_clock, read_metrics, time_to_target  # noqa: PLC0415

    name = os.path.basename(run_dir)
    gpus, mode, seed = parse_name(name)
    row = {"name": name, "gpus": gpus, "mode": mode, "seed": seed}
    try:
        rows = read_metrics(run_dir)
        summary = read_summary(run_dir)
    except (FileNotFoundError, ValueError) as e:
        return {**row, "error": str(e)}
    evals = [r for r in rows if r.get(key) is not None]
    row.update({
        "device": summary.get("device"), "num_envs_per_gpu": summary.get("num_envs"),
        "num_envs_total": summary.get("num_envs_total"), "iterations": summary.get("iterations"),
        "samples_per_s": summary.get("steady_samples_per_s_median"),
        "iteration_ms": 1e3 * (summary.get("steady_phase_s_median") or {}).get("iteration_s", math.nan),
        "phase_ms": {k[len("phase/"):-2]: 1e3 * v for k, v in (summary.get("steady_phase_s_median") or {}).items()
                     if k.startswith("phase/") and v is not None},
        "first_iteration_s": summary.get("first_iteration_time_s"),
        "to_target": {f"{v:g}": time_to_target(rows, key, v, smooth) for v in values},
        # the learning time the whole run had: a target it missed lies beyond it
        "learned_s": learning_clock(rows)[-1] if rows else 0.0,
        "last": {k: evals[-1].get(k) for k in ("time_s", "samples", key)} if evals else None,
        "evaluations": len(evals), "evaluation_s": round(sum(r.get("eval_s", 0.0) for r in rows), 2),
        "update": update_medians(rows),
        # each evaluation's iteration, value and the policy's noise then: what a run had learnt by an iteration
        "by_iteration": [[r["iteration"], r[key], r.get("policy/noise_std")] for r in evals],
    })
    return row


def update_medians(rows: list[dict]) -> dict:
    """What the KL rule did in a run: the median, over its last four fifths of iterations (the rule has settled),
    of the updates' mean KL and mean learning rate (``policy/kl``, ``policy/lr_mean``; None where not logged)."""
    late = rows[len(rows) // 5:]
    out = {}
    for name, key in (("kl", "policy/kl"), ("lr", "policy/lr_mean")):
        values = [r[key] for r in late if r.get(key) is not None]
        out[name] = statistics.median(values) if values else None
    return out


def stopped_rows(doc: dict, runs_dir: str) -> list[str]:
    """Rows for the runs in ``runs_dir`` that ``doc`` lacks, added to it; their names. A benchmark stopped while jobs
    ran (a SIGTERM: a device call's time limit) stops them too, and a run stopped on request still writes its
    summary, so its rows up to the stop count: one that had not reached the last target is a seed cut short,
    whose learning time is the bound of its miss (censored_median), with a note saying so."""
    known = {r["name"] for r in doc["runs"]}
    key, values = doc["targets"]["key"], tuple(doc["targets"]["values"])
    added = []
    for d in sorted(glob.glob(os.path.join(runs_dir, "gpu*-seed*"))):
        name = os.path.basename(d)
        if name in known or not os.path.isfile(os.path.join(d, "summary.json")):
            continue
        row = run_row(d, key, values, doc.get("smooth", 1))
        if "error" in row:
            continue
        row.update(exit_code=None, num_envs=doc.get("num_envs"), train_flags=doc.get("train_flags", ""),
                   seconds=doc["seconds"])
        if row["to_target"].get(f"{max(values):g}") is None:
            row["note"] = (f"still running when the benchmark was stopped (a call's time limit), short of the target after "
                           f"{row['learned_s']:.0f} s of learning")
        doc["runs"].append(row)
        added.append(name)
    return added


def censored_median(hits: list[dict | None], bounds: list[float]) -> tuple[float, float]:
    """The median learning time over seeds, as the interval (low, high) that it lies in. A seed that missed the
    target took longer than the learning time it had (its bound) and may have taken for ever: the median with
    the bounds in those seeds' places is the low end, with infinity in their places the high end. Runs of one
    length give an exact median (low == high) or a lower bound (high infinite); runs of several lengths, joined,
    can give an interval between."""
    reached = [h["learning_s"] if h else None for h in hits]
    low = statistics.median(b if s is None else s for s, b in zip(reached, bounds))
    high = statistics.median(math.inf if s is None else s for s in reached)
    return low, high


def ratio_of(line: dict, base: dict | None) -> tuple[float, float] | None:
    """The interval G GPUs' median over one GPU's lies in, from both medians' intervals."""
    if base is None:
        return None
    low = line["median_learning_s"] / base["median_upper_s"] if base["median_upper_s"] > 0 else math.inf
    high = line["median_upper_s"] / base["median_learning_s"] if base["median_learning_s"] > 0 else math.inf
    return low, high


def groups(doc: dict) -> dict[tuple[int, str], list[dict]]:
    out: dict[tuple[int, str], list[dict]] = {}
    for r in doc["runs"]:
        if "error" not in r:
            out.setdefault((r["gpus"], r["mode"]), []).append(r)
    # by GPUs; the plain 1-GPU line (the baseline) before its labelled controls; then by envs per GPU, so "-+8k"
    # comes before "-+16k" in the table and the figures' legends
    return dict(sorted(out.items(), key=lambda item: (
        item[0][0], item[0][1] != "-", min(r.get("num_envs_per_gpu") or 0 for r in item[1]), item[0][1])))


def summarize(doc: dict) -> list[dict]:
    """One line per (GPUs, mode): medians over seeds, and the ratios to one GPU's medians. The baseline is one
    GPU with the plain flags (mode "-"); a 1-GPU line made with other flags (a control, "-+label") is measured
    against it too, as every multi-GPU line is."""
    lines = []
    base: dict[str, dict] = {}
    base_rate = math.nan
    for (gpus, mode), runs in groups(doc).items():
        line = {"gpus": gpus, "mode": mode, "seeds": sorted(r["seed"] for r in runs),
                "samples_per_s": statistics.median(r["samples_per_s"] or 0.0 for r in runs),
                "iteration_ms": statistics.median(r["iteration_ms"] for r in runs),
                "first_iteration_s": statistics.median(r["first_iteration_s"] or math.nan for r in runs),
                "targets": {}}
        if gpus == 1 and math.isnan(base_rate):
            base_rate = line["samples_per_s"]
        line["samples_speedup"] = line["samples_per_s"] / base_rate if base_rate else math.nan
        for v in doc["targets"]["values"]:
            hits = [r["to_target"].get(f"{v:g}") for r in runs]
            learn, upper = censored_median(hits, [r.get("learned_s", 0.0) for r in runs])
            walls = [h["time_s"] if h else math.inf for h in hits]
            t = {"reached": sum(h is not None for h in hits), "runs": len(hits),
                 "learning_s": [h["learning_s"] if h else None for h in hits],
                 "bounds_s": [None if h else r.get("learned_s") for h, r in zip(hits, runs)],
                 "median_learning_s": learn, "median_upper_s": upper, "exact": learn == upper,
                 "median_time_s": statistics.median(walls)}
            first = gpus == 1 and f"{v:g}" not in base
            if first:
                base[f"{v:g}"] = t
            t["ratio"] = ((1.0, 1.0) if t["exact"] else None) if first else ratio_of(t, base.get(f"{v:g}"))
            line["targets"][f"{v:g}"] = t
        lines.append(line)
    return lines


GOAL = {2: 0.7, 4: 0.5}  # issue 54: G GPUs' median learning time to target at most this share of one GPU's


def seconds(v: float) -> str:
    return "not reached" if v == math.inf else ("-" if v is None or math.isnan(v) else f"{v:.1f} s")


def verdict(ratio: tuple[float, float], goal: float | None) -> str:
    """'met', 'not met', or 'open' where the ratio's interval holds the goal."""
    if goal is None:
        return ""
    low, high = ratio
    return f"; <= {goal}: " + ("met" if high <= goal else "not met" if low > goal else "open")


def interval(low: float, high: float, unit: str, digits: int) -> str:
    """'12.0 s', '> 12.0 s' (no end known), '< 0.36x' (no start), '40.1-52.3 s'."""
    if low == high:
        return f"{low:.{digits}f}{unit}"
    if high == math.inf:
        return f"> {low:.{digits}f}{unit}"
    if low == 0:
        return f"< {high:.{digits}f}{unit}"
    return f"{low:.{digits}f}-{high:.{digits}f}{unit}"


def setting(line: dict) -> str:
    """A summary line's name in the report's sentences: '1 GPU -', '4 GPUs split-horizon'."""
    return f"{line['gpus']} GPU{'s' if line['gpus'] > 1 else ''} {line['mode']}"


def target_cells(t: dict, gpus: int) -> str:
    each = ", ".join(seconds(s) if s is not None else f"> {b:.0f} s" for s, b in zip(t["learning_s"], t["bounds_s"]))
    median = interval(t["median_learning_s"], t["median_upper_s"], " s", 1)
    ratio = "" if t["ratio"] is None or t["ratio"] == (0, math.inf) else \
        f" ({interval(*t['ratio'], 'x', 2)}{verdict(t['ratio'], GOAL.get(gpus))})"
    return f"{each} | {median}{ratio}, {t['reached']} of {t['runs']}"


def iterations_line(doc: dict, lines: list[dict], value: float, grouped: dict) -> str:
    """Each seed's iterations to ``value``: how much one iteration learns, which decides what G GPUs give when their
    iterations take as long as one GPU's (grow-kl: G times the samples an iteration)."""
    def cell(r: dict) -> str:
        hit = r["to_target"].get(f"{value:g}")
        return str(hit["iteration"]) if hit else f"> {r.get('iterations') or 0}"

    return (f"Iterations to {doc['targets']['key']} {value:g}, each seed (\"> N\": a seed that missed it in its N): "
            + "; ".join(f"{setting(ln)}: "
                        + ", ".join(cell(r) for r in grouped[(ln["gpus"], ln["mode"])]) for ln in lines) + ".")


def common_iteration(value: float, grouped: dict) -> int | None:
    """The iteration at which to set the settings side by side: the median, over the 1-GPU baseline's runs that
    reached ``value``, of their iterations to it (None where none did)."""
    base = grouped.get((1, "-"), [])
    hits = [h["iteration"] for h in (r["to_target"].get(f"{value:g}") for r in base) if h]
    return int(statistics.median(hits)) if hits else None


def by_iteration_line(doc: dict, lines: list[dict], value: float, grouped: dict) -> str:
    """What each setting had learnt by one iteration (common_iteration): each run's last evaluation at or before it,
    with the iteration it came at and the policy's noise then, ranged over the runs that got that far. Runs that
    stopped at the target sooner count with the evaluation that reached it (not the one they close with); runs cut
    before it are left out."""
    at = common_iteration(value, grouped)
    if at is None:
        return ""
    cells = []
    for ln in lines:
        runs = grouped[(ln["gpus"], ln["mode"])]
        got = []
        for r in runs:
            hit = r["to_target"].get(f"{value:g}")
            if (r.get("iterations") or 0) < at and not hit:
                continue  # cut before the iteration: what it would have had is not known
            last = min(at, hit["iteration"]) if hit else at  # not the closing evaluation a run makes after its hit
            before = [e for e in r.get("by_iteration") or [] if e[0] <= last]
            if before:
                got.append(before[-1])
        name = setting(ln)
        if not got:
            cells.append(f"{name}: - (0 of {len(runs)} runs got that far)")
            continue
        noise = [e[2] for e in got if e[2] is not None]
        values = [e[1] for e in got]
        digits = 0 if max(map(abs, values)) >= 100 else 2  # returns in whole points, speeds in cm/s
        cells.append(f"{name}: {spread(values, digits)} at iterations {spread([e[0] for e in got], 0)}"
                     + (f", noise std {spread(noise, 2)}" if noise else "") + f" ({len(got)} of {len(runs)} runs)")
    return (f"By iteration {at} (one GPU's median iterations to {doc['targets']['key']} {value:g}), each run's last "
            "evaluation at or before it, over the runs that got that far: " + "; ".join(cells) + ".")


def spread(values: list[float], digits: int, scientific: bool = False) -> str:
    """'0.010-0.011'; with ``scientific``, one power of ten for both ends, '1.7-2.1e-4'; one value alone."""
    low, high = min(values), max(values)
    power = math.floor(math.log10(high)) if scientific and high > 0 else 0
    low, high = f"{low / 10 ** power:.{digits}f}", f"{high / 10 ** power:.{digits}f}"
    return (low if low == high else f"{low}-{high}") + (f"e{power}" if scientific else "")


def update_line(lines: list[dict], grouped: dict) -> str:
    """The KL rule's settled state per setting, over its seeds: the ranges the docs quote beside the iterations."""
    cells = []
    for ln in lines:
        done = [r["update"] for r in grouped[(ln["gpus"], ln["mode"])] if (r.get("update") or {}).get("kl") is not None]
        if done:
            rates = [u["lr"] for u in done if u["lr"] is not None]
            cells.append(f"{setting(ln)}: KL "
                         f"{spread([u['kl'] for u in done], 4)}, learning rate {spread(rates, 1, True) if rates else '-'}")
    return ("The KL rule, each run's median over its last four fifths of iterations (the updates' mean KL; the mean "
            "learning rate), over the seeds: " + "; ".join(cells) + ".") if cells else ""


def days(doc: dict) -> str:
    """The day the runs were made, or the first and last of the days of joined outputs."""
    dates = doc.get("dates", [doc["date"]])
    return dates[0] if len(dates) == 1 else f"{dates[0]} to {dates[-1]}"


def timed_by(doc: dict) -> str:
    """How the table's targets are read: evaluations at a gap, or the training rows (their running mean)."""
    key, smooth = doc["targets"]["key"], doc.get("smooth", 1)
    mean = f" (the mean of {smooth} rows)" if smooth > 1 else ""
    return f"evaluated every {doc['eval_gap']:g} s{mean}" if key.startswith("eval/") else f"read from the training rows{mean}"


def markdown(doc: dict, lines: list[dict]) -> str:
    key, values = doc["targets"]["key"], doc["targets"]["values"]
    devices = sorted({r.get("device") for r in doc["runs"] if r.get("device")})
    lengths = [r.get("seconds", doc["seconds"]) for r in doc["runs"]]
    limits = (min(lengths), max(lengths)) if lengths else ()
    out = [f"{doc['task']}: time to {key} " + " and ".join(f"{v:g}" for v in values)
           + f"; runs of at most {interval(*limits, ' s', 0) if limits else ''}, " + timed_by(doc) + "; "
           f"{', '.join(devices)} ({doc['host_gpus']} GPUs of one host), {days(doc)}", "",
           "| GPUs | mode | envs per GPU | samples/s | x 1 GPU | iteration ms | first iteration | "
           + " | ".join(f"{key} {v:g}: learning time, each seed | median (ratio; goal)" for v in values) + " |",
           "|---:|---|---:|---:|---:|---:|---:|" + "---|---|" * len(values)]
    grouped = groups(doc)
    for line in lines:
        runs = grouped[(line["gpus"], line["mode"])]
        envs = "/".join(sorted({str(r["num_envs_per_gpu"]) for r in runs}))
        speedup = "-" if math.isnan(line["samples_speedup"]) else f"{line['samples_speedup']:.2f}x"
        out.append(f"| {line['gpus']} | {line['mode']} | {envs} | {line['samples_per_s'] / 1e6:.3f} M | {speedup} | "
                   f"{line['iteration_ms']:.1f} | {line['first_iteration_s']:.1f} s | "
                   + " | ".join(target_cells(line["targets"][f"{v:g}"], line["gpus"]) for v in values) + " |")
    notes = [f"{r['name']}: {r['note']}" for r in doc["runs"] if r.get("note")]
    flags = sorted({(r["mode"], r.get("num_envs"), r.get("train_flags", "")) for r in doc["runs"]
                    if r.get("num_envs") or r.get("train_flags")})
    reached = ("the start of the first evaluation that reached the target" if doc["targets"]["key"].startswith("eval/")
               else f"the first training row whose mean over {doc.get('smooth', 1)} rows reached the target")
    out += ["", f"Learning time: from the run's first iteration to {reached}, evaluations left out; "
            "\"> T\": a seed that missed it in the T s of learning it had, and a median "
            "that falls on such seeds, a lower bound (a ratio against it an upper bound, \"<\"); where runs of several "
            "lengths are joined, \"A-B s\": the median lies between. "
            "From the process start (wall-clock, start-up and evaluations included), medians: "
            + "; ".join(f"{setting(ln)}: "
                        + ", ".join(seconds(ln['targets'][f'{v:g}']['median_time_s']) for v in values)
                        for ln in lines) + "."]
    out.append(iterations_line(doc, lines, values[-1], grouped))
    if doc["targets"]["key"].startswith("eval/"):  # a training row's value is in the table already
        out += [b for b in [by_iteration_line(doc, lines, values[-1], grouped)] if b]
    out += [u for u in [update_line(lines, grouped)] if u]
    out += [f"{mode}: --num-envs {n or 'default'} {f}".rstrip() + "." for mode, n, f in flags]
    out += [f"{n}." for n in notes]
    return "\n".join(out) + "\n"


def figures(doc: dict, runs_dir: str, out: str) -> list[str]:
    """The target's key against learning time (agents.logger.learning_clock) and against samples, every run, one
    colour per (GPUs, mode)."""
    try:
        import matplotlib  # noqa: PLC0415
    except ImportError:
        print("matplotlib is not installed: no figures (draw them later with --report)", flush=True)
        return []
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    from agents.logger import learning_clock, read_metrics  # noqa: PLC0415

    key, values = doc["targets"]["key"], doc["targets"]["values"]
    paths = []
    axes = (("time", "learning time: wall-clock seconds since the first iteration, evaluations left out"),
            ("samples", "samples (env steps)"))
    for axis, label in axes:
        fig, ax = plt.subplots(figsize=(7.5, 4.5))
        for i, ((gpus, mode), runs) in enumerate(groups(doc).items()):
            for j, r in enumerate(runs):
                rows = read_metrics(os.path.join(runs_dir, r["name"]))
                xs = learning_clock(rows) if axis == "time" else [x["samples"] for x in rows]
                pts = [(x, row[key]) for x, row in zip(xs, rows) if row.get(key) is not None]
                ax.plot([p[0] for p in pts], [p[1] for p in pts], color=f"C{i}", lw=1.2, alpha=0.8,
                        label=f"{gpus} GPU{'s' if gpus > 1 else ''}{'' if mode == '-' else ', ' + mode.lstrip('-')}"
                        if j == 0 else None)
        for v in values:
            ax.axhline(v, color="grey", ls=":", lw=0.8)
        ax.set_xlabel(label)
        ax.set_ylabel(f"{key} (deterministic policy)" if key.startswith("eval/") else f"{key} (training episodes)")
        ax.set_title(f"{doc['task']}: PPO on 1 to {max(r['gpus'] for r in doc['runs'])} GPUs")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = os.path.join(out, f"{doc['task'].lower()}_gpus_{key.replace('/', '_')}_vs_{axis}.png")
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def write_report(doc: dict, runs_dir: str, out: str) -> str:
    doc["summary"] = summarize(doc)
    write_json(os.path.join(out, f"scaling_{doc['task']}.json"), doc)
    table = markdown(doc, doc["summary"])
    with open(os.path.join(out, f"scaling_{doc['task']}.md"), "w") as f:
        f.write(table)
    figures(doc, runs_dir, out)
    return table


def task_json(folder: str, task: str) -> str:
    """The folder's scaling_<task>.json, or its only scaling JSON (a folder may hold several tasks' reports)."""
    found = sorted(glob.glob(os.path.join(folder, "scaling_*.json")))
    mine = os.path.join(folder, f"scaling_{task}.json")
    if mine in found or len(found) == 1:
        return mine if mine in found else found[0]
    if not found:
        raise SystemExit(f"--report {folder}: no scaling_<task>.json there")
    tasks = ", ".join(os.path.basename(f)[len("scaling_"):-len(".json")] for f in found)
    raise SystemExit(f"--report {folder}: it holds the reports of {tasks} but not {task}: name one with --task")


def report(folders: list[str], task: str = "Ant", targets: str | None = None) -> int:
    """Join the runs of one or more outputs for one task (a grid split over calls) into the first's report;
    ``targets`` (KEY=V1,V2) times the runs to other values of a logged key, read again from their metrics."""
    docs = []
    for folder in folders:
        with open(task_json(folder, task)) as f:
            docs.append((folder, json.load(f)))
    first = docs[0][1]
    same = ("task", "targets", "eval_gap", "smooth")  # runs of other lengths join: each run's misses bound them
    for _, doc in docs:
        doc.setdefault("smooth", 1)
        for r in doc["runs"]:
            r.setdefault("seconds", doc["seconds"])
    for folder, doc in docs[1:]:
        if [doc[k] for k in same] != [first[k] for k in same]:
            raise SystemExit(f"--report: {folder} has {', '.join(f'{k} {doc[k]}' for k in same)} and the first output "
                             f"{', '.join(f'{k} {first[k]}' for k in same)}: join runs timed alike")
    out = docs[0][0]
    loose = os.path.join(out, f"runs_{first['task']}")
    first_packed = os.path.exists(loose + ".tar.gz")
    # a packed output's runs are read from a folder of this call's own: two reports of one committed folder at once
    # (the docs' checks run beside each other) must not unpack into, and remove, the same folder
    if not first_packed:
        return joined_report(docs, first, out, loose, first_packed, targets)
    with tempfile.TemporaryDirectory(prefix="scaling-") as tmp:
        return joined_report(docs, first, out, os.path.join(tmp, f"runs_{first['task']}"), first_packed, targets)


def joined_report(docs: list, first: dict, out: str, runs_dir: str, first_packed: bool, targets: str | None) -> int:
    for folder, doc in docs:
        gather_runs(folder, doc, runs_dir)
    names = {r["name"] for r in first["runs"]}
    for _, doc in docs[1:]:  # a run in several outputs: the first output's is kept
        for r in doc["runs"]:
            if r["name"] not in names:
                first["runs"].append(r)
                names.add(r["name"])
    # outputs made under CUDA_VISIBLE_DEVICES see part of the host (1-GPU baselines on GPUs 0,1 beside a job on 2,3)
    first["host_gpus"] = max(doc.get("host_gpus", 0) for _, doc in docs)
    first["dates"] = sorted({d for _, doc in docs for d in doc.get("dates", [doc["date"]])})
    if targets:
        key, values = parse_targets(targets)
        first["targets"] = {"key": key, "values": list(values)}
    key, values = first["targets"]["key"], tuple(first["targets"]["values"])
    for r in first["runs"]:  # read again from the runs' files, as this version of the script reads them
        r.update(run_row(os.path.join(runs_dir, r["name"]), key, values, first.get("smooth", 1)))
    print(write_report(first, runs_dir, out), flush=True)
    if len(docs) > 1 or not first_packed:  # the first output now holds every run: its report can be drawn again alone
        pack_runs(runs_dir, out, first["task"])
    if not first_packed:  # its loose runs are in the archive now (a report that fails keeps them)
        shutil.rmtree(runs_dir)
    return 0


def gather_runs(folder: str, doc: dict, runs_dir: str) -> None:
    """One output's run folders into ``runs_dir``, beside those already there (a name already there is kept). An
    output is packed (runs_<task>.tar.gz) or, where its benchmark was stopped before it packed, still a folder
    (runs_<task>/), whose runs the JSON may lack: their rows are read from their files (stopped_rows)."""
    loose = os.path.join(folder, f"runs_{doc['task']}")
    packed = loose + ".tar.gz"
    if not os.path.exists(packed):
        if not os.path.isdir(loose):
            raise SystemExit(f"--report {folder}: neither runs_{doc['task']}.tar.gz nor runs_{doc['task']}/ is there")
        for name in stopped_rows(doc, loose):
            print(f"{name}: not in {folder}'s JSON (its benchmark was stopped); read from its files", flush=True)
    if os.path.abspath(loose) == os.path.abspath(runs_dir) and not os.path.exists(packed):
        return  # the first output's own folder: already in place
    with tempfile.TemporaryDirectory() as tmp:
        source = loose
        if os.path.exists(packed):
            with tarfile.open(packed) as tar:
                tar.extractall(tmp, filter="data")
            source = os.path.join(tmp, f"runs_{doc['task']}")
        os.makedirs(runs_dir, exist_ok=True)
        for entry in os.listdir(source):
            if not os.path.exists(os.path.join(runs_dir, entry)):
                (shutil.copytree if os.path.isdir(os.path.join(source, entry)) else shutil.copy2)(
                    os.path.join(source, entry), os.path.join(runs_dir, entry))


def pack_runs(runs_dir: str, out: str, task: str) -> None:
    path = os.path.join(out, f"runs_{task}.tar.gz")
    with tarfile.open(path + ".tmp", "w:gz") as tar:
        tar.add(runs_dir, arcname=f"runs_{task}",
                filter=lambda ti: None if ti.name.endswith((".pt", "metrics.csv")) or "/tensorboard" in ti.name else ti)
    os.replace(path + ".tmp", path)


def keep_checkpoints(runs_dir: str, to: str) -> list[str]:
    """Each run's last checkpoint (``<run>/checkpoint.pt``) copied to ``to/<run>.pt``; the names kept."""
    kept = []
    for name in sorted(os.listdir(runs_dir)):
        src = os.path.join(runs_dir, name, "checkpoint.pt")
        if os.path.isfile(src):
            os.makedirs(to, exist_ok=True)
            shutil.copyfile(src, os.path.join(to, f"{name}.pt"))
            kept.append(name)
    return kept


def main(argv=None) -> int:
    from agents.data_parallel import DEFAULT, MODES  # noqa: PLC0415

    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="output folder")
    ap.add_argument("--report", nargs="+", metavar="OUT", help="write the table and figures again from these outputs")
    ap.add_argument("--task", default="Ant")
    ap.add_argument("--gpus", type=int, nargs="+", default=[1, 2, 4],
                    help="GPU counts (default: 1 2 4); without 1 there is no baseline here, and the ratios come when "
                         "--report joins this output with one that has it")
    ap.add_argument("--modes", nargs="+", default=None, choices=MODES,
                    help=f"--multi-gpu modes to compare (default: the task's preset, as train picks it: {DEFAULT}, "
                         "split-horizon for Gymnasium's tasks)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1], help="seeds of each multi-GPU setting")
    ap.add_argument("--baseline-seeds", type=int, nargs="+", default=None, help="seeds of the 1-GPU runs (default: --seeds)")
    ap.add_argument("--targets", default=None, metavar="KEY=V1,V2",
                    help="what to time, e.g. eval/speed=8,9.5 (default: the task's, TARGETS above)")
    ap.add_argument("--num-envs", type=int, default=None,
                    help="train's --num-envs (default: train's; under split the total, else per GPU)")
    ap.add_argument("--seconds", type=float, default=180.0,
                    help="the longest a run may train, wall-clock from its start with its evaluations (default 180; "
                         "the suite's evaluations take 40-47 %% of a run at --eval-gap 20: give the learning time "
                         "a target needs about twice)")
    ap.add_argument("--eval-gap", type=float, default=5.0, help="seconds between evaluations (default 5)")
    ap.add_argument("--smooth", type=int, default=1, metavar="N",
                    help="a target is reached when the mean of the key's last N logged values reaches it (default "
                         "1; 3 for a training return, as mjlab_side_by_side reads it)")
    ap.add_argument("--stop", type=float, default=None, metavar="VALUE",
                    help="each run stops once the key reaches VALUE in one logged row (default: the last target, "
                         "with --smooth 1; with --smooth N, none: give a value past the last target, or the runs "
                         "train --seconds)")
    ap.add_argument("--train-flags", default="", help="more `warpgym train` flags for every run, quoted")
    ap.add_argument("--label", default="", help="a name for runs made with other flags (--num-envs, --train-flags), "
                                               "added to their setting (split+LABEL), so --report keeps them apart")
    ap.add_argument("--repeat", type=int, default=1, metavar="N",
                    help="these runs are the Nth of their seeds: names end in -rN, so --report keeps them beside "
                         "the first (where a name repeats, it keeps the first output's run)")
    ap.add_argument("--keep-checkpoints", action="store_true",
                    help="keep each run's last checkpoint as OUT/checkpoints/<run>.pt (the archive has none), for "
                         "`warpgym eval` to score in Gymnasium's env")
    ap.add_argument("--device", choices=("cuda", "cpu"), default="cuda",
                    help="cpu: a rehearsal of the whole benchmark on the CPU, each 'GPU' a share of the cores (to "
                         "check a grid before a GPU machine runs it; its times mean nothing)")
    args = ap.parse_args(argv)
    if args.report:
        try:
            return report(args.report, args.task, args.targets)
        except ValueError as e:
            ap.error(str(e))
    if not args.out:
        ap.error("--out is required (or --report OUT)")
    if min(args.gpus) < 1:
        ap.error(f"--gpus {' '.join(map(str, args.gpus))}: each is a number of GPUs, 1 or more")
    if not (args.seconds > 0 and args.eval_gap > 0) or (args.num_envs is not None and args.num_envs < 1):
        ap.error(f"--seconds {args.seconds}, --eval-gap {args.eval_gap}, --num-envs {args.num_envs}: must be positive")
    from warpgym.tasks.presets import PRESETS  # noqa: PLC0415

    if args.task not in PRESETS:
        ap.error(f"--task {args.task}: choose one of {', '.join(PRESETS)}")
    try:
        key, values = parse_targets(args.targets) if args.targets else default_targets(args.task)
    except ValueError as e:
        ap.error(str(e))
    args.baseline_seeds = args.baseline_seeds or args.seeds
    if args.smooth < 1:
        ap.error(f"--smooth {args.smooth}: the number of logged values averaged, 1 or more")
    if args.stop is None and args.smooth == 1:
        args.stop = max(values)
    elif args.stop is not None and args.stop < max(values):
        ap.error(f"--stop {args.stop:g} is below the last target {max(values):g}: the runs would stop before it")
    args.modes = args.modes or [preset_mode(args.task)]
    if args.repeat < 1:
        ap.error(f"--repeat {args.repeat}: the run's number among runs of the same seeds, 1 or more")
    if any(c in args.label for c in "-/ ") or "seed" in args.label:
        ap.error(f"--label {args.label!r}: letters, digits, '+' and '_' only, e.g. --label 16k")

    import torch  # noqa: PLC0415

    available = torch.cuda.device_count() if args.device == "cuda" else max(args.gpus)
    if args.device == "cpu":
        args.train_flags += " --device cpu"
    if max(args.gpus) > available:
        raise SystemExit(f"--gpus {' '.join(map(str, args.gpus))}: this host has {available} GPU(s); pass counts up "
                         f"to {available}" + (" (scaling.py measures GPUs: run it on a GPU machine)" if not available
                                               else ""))
    # a SIGTERM (a time limit's) ends the jobs too, and what finished is already in the JSON
    signal.signal(signal.SIGTERM, lambda signum, frame: sys.exit(128 + signum))
    out = os.path.abspath(args.out)
    runs = os.path.join(out, f"runs_{args.task}")
    os.makedirs(runs, exist_ok=True)
    say = lambda s: print(f"[{time.strftime('%H:%M:%S')}] {s}", flush=True)  # noqa: E731
    doc = {"task": args.task, "targets": {"key": key, "values": list(values)}, "smooth": args.smooth,
           "stop": args.stop, "seconds": args.seconds,
           "eval_gap": args.eval_gap, "num_envs": args.num_envs, "train_flags": args.train_flags,
           "host_gpus": available, "date": time.strftime("%Y-%m-%d"), "runs": []}

    say(f"warm-up: {args.task} compiles its kernels once, so every timed run starts on a warm cache")
    warm = os.path.join(runs, "warmup")
    codes = run_jobs([Job("warmup", 1, [*TRAIN, "--task", args.task,
                                        "--num-envs", "256" if args.device == "cuda" else "8", "--max-iterations", "3",
                                        "--eval-gap", "0", *(["--device", "cpu"] if args.device == "cpu" else []),
                                        "--run-dir", warm, "--no-plots"], warm + ".log", cwd=ROOT)], available, say=say)
    if codes["warmup"] != 0:
        with open(warm + ".log") as f:
            raise SystemExit(f"the warm-up run failed ({codes['warmup']}):\n{f.read()[-3000:]}")
    shutil.rmtree(warm)

    def done(job: Job, code: int) -> None:
        row = run_row(os.path.join(runs, job.name), key, values, args.smooth)
        row.update(exit_code=code, num_envs=args.num_envs, train_flags=args.train_flags, seconds=args.seconds)
        doc["runs"].append(row)
        write_json(os.path.join(out, f"scaling_{args.task}.json"), doc)  # what ended is kept, whatever follows
        hits = ", ".join(f"{v}: {h['learning_s']:.1f} s" if h else f"{v}: -" for v, h in row.get("to_target", {}).items())
        say(f"{job.name}: {hits or row.get('error')}")

    try:
        run_jobs(jobs_for(args, runs, key, args.stop), available, on_done=done, say=say)
    finally:  # also when stopped (SIGTERM): the runs it stopped still count, as far as they went
        for name in stopped_rows(doc, runs):
            say(f"{name}: stopped with the benchmark; its rows up to the stop are kept")
        if doc["runs"]:
            print(write_report(doc, runs, out), flush=True)
            pack_runs(runs, out, args.task)
            if args.keep_checkpoints:
                keep_checkpoints(runs, os.path.join(out, "checkpoints"))
            shutil.rmtree(runs)
    return 0


if __name__ == "__main__":
    sys.exit(main())
