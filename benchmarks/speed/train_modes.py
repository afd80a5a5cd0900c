"""Which way of running `warpgym train` starts soonest and trains fastest? Each mode is a set of its flags; one
script run compares them on one task and one GPU, side by side.

    python -m benchmarks.speed.train_modes --out OUT --task Ant                       # sequential against --overlap
    python -m benchmarks.speed.train_modes --out OUT --task Humanoid --modes sequential compiled --seconds 240
    python -m benchmarks.speed.train_modes --out OUT --task Hopper-v5 --modes sequential step-graph no-graph \\
        --throughput-seconds 45 --repeats 3                                      # how the rollout is captured
    python -m benchmarks.speed.train_modes --report OUT/train_modes_Ant.json     # the tables again
    python -m benchmarks.speed.train_modes --out OUT --task Ant --envs 16 --batch-size 64 --throughput-seconds 20 \\
        --repeats 1 --seconds 30 --seeds 0 --device cpu                              # a smoke run on a CPU

The modes (`MODES`): sequential (the default: the rollout captured as one CUDA graph, then the update), overlap
(--overlap: the next rollout collected during the update), compiled (--compile-update: the loss under
torch.compile), overlap+compiled, step-graph (--rollout-graph step: one env step's graph replayed horizon_len
times) and no-graph (--rollout-graph off: each step launched from Python). Any task of the registry.

In one script run, for one task at --envs envs (the kernel cache warmed by the first two parts):
  ceiling     the task env's env-steps/s (`warpgym bench --tasks`, median of 3 timings): what training could reach;
  warm-up     one short run of the first mode, not counted (a start's imports, compiles and captures fill caches);
  throughput  --repeats rounds, each running every mode for --throughput-seconds, the order turning each round so
              that a drift of the machine falls on every mode alike. Per run: "ready", its first_iteration_time_s
              (when the first iteration's row was logged, after the second iteration's captures), its steady
              samples/s (the median of its iterations) and median phase times (sequential: collect, update;
              overlapped: update, then "collect", the part of the rollout the update did not hide). The table
              holds the medians over the rounds and their ratios to the first mode's;
  learning    for a task with target speeds (Ant, Humanoid: benchmarks.targets), a --seconds run per mode and
              seed: when its training episodes first reached each target, and the median over the seeds (none
              unless most seeds got there). A run ends at its last target (--keep-going: it trains the whole time).
Writes OUT/train_modes_<task>.json after every run (a crash loses nothing measured) and the tables as
OUT/train_modes_<task>.md. --report also reads the JSON that this script's two forerunners kept
(benchmarks/speed/overlap.py's and rollout_capture.py's, under docs/bench/).
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

from benchmarks.harness import read_report
from benchmarks.speed import envs_per_gpu as epg  # the runs, the bench, the stop at targets and the JSON writes
from benchmarks.targets import TARGETS

MODES = {"sequential": (), "overlap": ("--overlap",), "compiled": ("--compile-update",),
         "overlap+compiled": ("--overlap", "--compile-update"), "step-graph": ("--rollout-graph", "step"),
         "no-graph": ("--rollout-graph", "off")}
# rollout_capture.py's names for the three ways of capturing the rollout ("rollout" was the default: sequential)
CAPTURE_NAMES = {"rollout": "sequential", "step": "step-graph", "off": "no-graph"}
PHASES = ("iteration_s", "phase/collect_s", "phase/update_s", "phase/idle_s")


def from_capture_report(doc: dict) -> list[dict]:
    """rollout_capture.py's JSON (``{"meta", "runs": {task: {mode: [run, ...]}}}``) as this script's documents, one
    per task, its ratios to the whole rollout's graph as that script's were; its runs carry no phases."""
    meta = doc.get("meta", {})
    out = []
    for task, by_mode in doc["runs"].items():
        by_mode = dict(sorted(by_mode.items(), key=lambda item: item[0] != "rollout"))
        rows = [{"mode": CAPTURE_NAMES.get(mode, mode), "round": k, "phase_s": None, **run}
                for mode, runs in by_mode.items() for k, run in enumerate(runs)]
        out.append({"task": task, "device": meta.get("gpu"), "num_envs": None, "date": meta.get("date"),
                    "command": meta.get("command"), "modes": [CAPTURE_NAMES.get(m, m) for m in by_mode],
                    "targets": [], "env_steps_per_s": None, "throughput": rows, "learning": []})
    return out


def medians(doc: dict) -> dict:
    """Per mode, in the document's order: the medians over its timed rounds of the ready time, samples/s and each
    phase, and how many rounds were timed (runs that failed or were too short to time are left out)."""
    def med(values):
        values = [v for v in values if v is not None]
        return statistics.median(values) if values else None

    out = {}
    for mode in dict.fromkeys([*doc.get("modes", []), *(r["mode"] for r in doc["throughput"])]):
        rows = [r for r in doc["throughput"] if r["mode"] == mode]
        timed = [r for r in rows if "error" not in r and not r.get("too_short") and r.get("samples_per_s")]
        if not rows:
            continue
        out[mode] = {"runs": len(timed), "of": len(rows), "ready_s": med(r.get("ready_s") for r in timed),
                     "samples_per_s": med(r["samples_per_s"] for r in timed),
                     "phase_s": {k: med((r.get("phase_s") or {}).get(k) for r in timed) for k in PHASES},
                     "not_timed": next((r.get("too_short") or r.get("error") for r in rows if r not in timed), None)}
    return out


def _ratio(value, base, digits: int) -> str:
    return f"{value / base:.{digits}f}" if value is not None and base else "-"


def tables(doc: dict) -> str:
    ceiling = doc.get("env_steps_per_s")
    envs = f" at {doc['num_envs']} envs" if doc.get("num_envs") else ""
    head = (f"task env: {epg.fmt_m(ceiling)} env-steps/s{envs} ({doc['device']})" if ceiling
            else f"{doc['task']}{envs} ({doc['device']})")
    by_mode = medians(doc)
    base = next(iter(by_mode.values()), {})
    first = next(iter(by_mode), "-")
    lines = [head, "", f"| mode | rounds timed | ready | samples/s | of env-steps/s | ready / {first}'s | samples/s / "
             f"{first}'s | iteration | collect | update | idle |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for mode, cell in by_mode.items():
        if not cell["runs"]:
            lines.append(f"| {mode} | 0 of {cell['of']} | not timed: {cell['not_timed']} | | | | | | | | |")
            continue
        ms = {k: f"{1e3 * v:.1f} ms" if v is not None else "-" for k, v in cell["phase_s"].items()}
        ready = f"{cell['ready_s']:.1f} s" if cell["ready_s"] is not None else "-"
        lines.append(f"| {mode} | {cell['runs']} of {cell['of']} | {ready} | {epg.fmt_m(cell['samples_per_s'])} | "
                     f"{_ratio(cell['samples_per_s'], ceiling, 2)} | {_ratio(cell['ready_s'], base.get('ready_s'), 2)} | "
                     f"{_ratio(cell['samples_per_s'], base.get('samples_per_s'), 3)} | {ms['iteration_s']} | "
                     f"{ms['phase/collect_s']} | {ms['phase/update_s']} | {ms['phase/idle_s']} |")
    targets = doc.get("targets") or []
    if doc.get("learning"):
        lines += ["", "| mode | seeds | " + " | ".join(f"time to {t} m/s (median; seeds there)" for t in targets)
                  + " | samples/s |", "|---|---:|" + "---:|" * (len(targets) + 1)]
        for mode, cell in epg.learning_by_size(doc, key="mode").items():
            lines.append(f"| {mode} | {cell['seeds']} | " + " | ".join(
                f"{epg.time_text(cell[t]['median_s'])} ({cell[t]['reached']}/{cell['seeds']})" for t in targets)
                + f" | {epg.fmt_m(cell['samples_per_s'])} |")
    return "\n".join(lines)


def report(paths: list[str]) -> str:
    docs = []
    for path in paths:
        doc = read_report(path, "a train_modes_<task>.json (or a kept overlap_*.json or rollout_capture_*.json)")
        docs += from_capture_report(doc) if "runs" in doc else [doc]
    return "\n\n".join(tables(doc) for doc in docs)


def throughput_row(mode: str, round_: int, run: dict, args) -> dict:
    """A mode's run of one round: its ready time, steady rate and phases; no rate from a run too short to time (a
    compiled run's first update compiles for seconds, so it needs a longer --throughput-seconds than the others)."""
    s = run["summary"]
    return epg.untimed({"mode": mode, "round": round_, "ready_s": s.get("first_iteration_time_s"),
                        "samples_per_s": s.get("steady_samples_per_s_median"), "phase_s": s.get("steady_phase_s_median"),
                        "peak_mib": run["peak_mib"], "iterations": s.get("iterations") or 0}, args.throughput_seconds)


def rounds(modes: list[str], repeats: int):
    """(round, mode) in the order they run: every mode once a round, the first one turning each round."""
    for k in range(repeats):
        for mode in modes[k % len(modes):] + modes[:k % len(modes)]:
            yield k, mode


def parse(argv):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="output directory")
    ap.add_argument("--report", nargs="+", metavar="JSON", help="print the tables of earlier runs' JSON")
    ap.add_argument("--task", default="Ant", help="any task of the registry (default Ant)")
    ap.add_argument("--envs", type=int, default=epg.BASE_ENVS)
    ap.add_argument("--modes", nargs="+", default=["sequential", "overlap"], choices=list(MODES),
                    help="the ways of training to compare, in this order; the first is the one the ratios are to")
    ap.add_argument("--throughput-seconds", type=float, default=60.0,
                    help="each throughput run, from its process's start (0: none, the learning runs only)")
    ap.add_argument("--repeats", type=int, default=1, help="rounds of throughput runs (default 1)")
    ap.add_argument("--no-warm-up", action="store_true", help="skip the uncounted first run")
    ap.add_argument("--seconds", type=float, default=None,
                    help="training time per learning run (Ant 180, Humanoid 240; tasks without targets have none)")
    ap.add_argument("--seeds", type=int, nargs="*", default=None,
                    help="seeds of the learning runs (default 0 1 2 for a task with target speeds; none: no "
                         "learning runs)")
    ap.add_argument("--bench-steps", type=int, default=100)
    ap.add_argument("--batch-size", type=int, default=None, help="the mini-batch (default: the task's)")
    ap.add_argument("--keep-going", action="store_true",
                    help="train every learning run for its whole time (default: stop it at the last target)")
    ap.add_argument("--device", default=None)
    args = ap.parse_args(argv)
    if args.report:
        return ap, args
    if not args.out:
        ap.error("--out is required (or --report JSON)")
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    try:
        task_entry(args.task)
    except (KeyError, ValueError) as e:
        ap.error(f"--task {args.task}: {e.args[0] if e.args else e}")
    if args.seeds is None:
        args.seeds = [0, 1, 2] if args.task in TARGETS else []
    if args.seeds and args.task not in TARGETS:
        ap.error(f"--seeds {' '.join(map(str, args.seeds))}: {args.task} has no target speeds to time (those that "
                 f"do: {', '.join(sorted(TARGETS))}); leave --seeds out to time the modes' throughput only")
    args.seconds = args.seconds or {"Ant": 180.0, "Humanoid": 240.0}.get(args.task, 0.0)
    if args.throughput_seconds < 0:
        ap.error(f"--throughput-seconds {args.throughput_seconds}: must be 0 (no throughput runs) or more")
    if not args.throughput_seconds and not args.seeds:
        ap.error("--throughput-seconds 0 with no learning runs: nothing to time; give it seconds or --seeds")
    for flag, v in (("--envs", args.envs), ("--repeats", args.repeats), ("--bench-steps", args.bench_steps),
                    ("--batch-size", args.batch_size or 1), ("--seconds", args.seconds if args.seeds else 1)):
        if not v > 0:
            ap.error(f"{flag} {v}: must be positive")
    args.scale_batch = False
    return ap, args


def main(argv=None) -> int:
    ap, args = parse(argv)
    if args.report:
        print(report(args.report))
        return 0
    if args.batch_size is not None:
        epg.BATCH[args.task] = args.batch_size
    import torch  # noqa: PLC0415

    from warpgym.sim.device import resolve_device  # noqa: PLC0415

    device = resolve_device(args.device)
    name = torch.cuda.get_device_name(torch.device(device)) if device.startswith("cuda") else "cpu"
    stem = args.task.replace(":", "_")
    runs = os.path.join(args.out, "runs")
    os.makedirs(runs, exist_ok=True)
    path = os.path.join(args.out, f"train_modes_{stem}.json")
    modes = list(dict.fromkeys(args.modes))
    doc = {"task": args.task, "device": name, "num_envs": args.envs, "date": time.strftime("%Y-%m-%d"),
           "command": " ".join(["python -m benchmarks.speed.train_modes", *(sys.argv[1:] if argv is None else argv)]),
           "modes": modes, "targets": list(TARGETS.get(args.task, ())), "env_steps_per_s": None,
           "throughput": [], "learning": []}
    doc["env_steps_per_s"] = epg.env_steps(args.task, args.envs, args)
    epg.save(path, doc)
    if args.throughput_seconds and not args.no_warm_up:
        epg.train(args.task, args.envs, min(args.throughput_seconds, 30.0), 0, os.path.join(runs, f"{stem}-warm-up"),
                  args, MODES[modes[0]])
    for k, mode in (rounds(modes, args.repeats) if args.throughput_seconds else ()):
        run = epg.train(args.task, args.envs, args.throughput_seconds, 0, os.path.join(runs, f"{stem}-{mode}-tp{k}"),
                        args, MODES[mode])
        doc["throughput"].append(throughput_row(mode, k, run, args))
        epg.save(path, doc)
    for seed in args.seeds:
        for mode in modes:  # the modes alternate, so a drifting machine touches both alike
            run = epg.train(args.task, args.envs, args.seconds, seed, os.path.join(runs, f"{stem}-{mode}-s{seed}"),
                            args, MODES[mode], stop_at=epg.stop_at(args))
            doc["learning"].append(epg.learning_row(run, args.task, seed, args.seconds, mode=mode))
            epg.save(path, doc)
    text = tables(doc)
    with open(os.path.join(args.out, f"train_modes_{stem}.md"), "w") as f:
        f.write(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
