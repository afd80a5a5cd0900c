"""Which way of running the PPO update trains fastest? Sequential against `--overlap` (the next rollout
collected during the update) and `--compile-update` (the loss under torch.compile), on one GPU.

    python -m benchmarks.speed.overlap --out OUT --task Ant
    python -m benchmarks.speed.overlap --out OUT --task Ant --modes sequential compiled
    python -m benchmarks.speed.overlap --out OUT --task Humanoid --seeds 0 1 2 --seconds 240
    python -m benchmarks.speed.overlap --out OUT --task Ant --envs 16 --batch-size 64 --throughput-seconds 20 \\
        --seconds 30 --seeds 0 --device cpu                                  # a smoke run on a CPU

In one script run, for one task at --envs envs (warm kernel cache: the first run fills it):
  ceiling     the task env's env-steps/s (`warpgym bench`, median of 3 timings): what training could reach;
  throughput  a --throughput-seconds run per mode: steady samples/s (median of its iterations), that
              as a ratio of the env-steps/s, and the median phase times (sequential: collect, update;
              overlapped: update, then "collect", the part of the rollout the update did not hide);
              a compiled run's first update compiles the loss, and its learning runs count that time;
  learning    a --seconds run per mode and seed: when the training episodes first reached each target
              speed (Ant 3 and 8 m/s, Humanoid 2 and 6 m/s), and the median over the seeds (none unless
              most seeds got there; envs_per_gpu.learning_by_size); a run ends at its last target
              (--keep-going: it trains the whole time).
Writes OUT/overlap_<task>.json after every run and the tables as OUT/overlap_<task>.md.
"""

from __future__ import annotations

import argparse
import os
import sys


from benchmarks.speed import envs_per_gpu as epg  # noqa: E402  (the runs, the bench and the JSON writes are the same)

MODES = {"sequential": (), "overlap": ("--overlap",), "compiled": ("--compile-update",),
         "overlap+compiled": ("--overlap", "--compile-update")}


def tables(doc: dict) -> str:
    ceiling = doc["env_steps_per_s"]
    lines = [f"task env: {epg.fmt_m(ceiling)} env-steps/s at {doc['num_envs']} envs ({doc['device']})", "",
             "| mode | samples/s | of env-steps/s | iteration | collect | update | idle |",
             "|---|---:|---:|---:|---:|---:|---:|"]
    for row in doc["throughput"]:
        if row.get("too_short"):
            lines.append(f"| {row['mode']} | not timed: {row['too_short']} | | | | | |")
            continue
        phase = row["phase_s"] or {}
        ms = {k: f"{1e3 * phase[k]:.1f} ms" if k in phase else "-" for k in
              ("iteration_s", "phase/collect_s", "phase/update_s", "phase/idle_s")}
        ratio = f"{row['samples_per_s'] / ceiling:.2f}" if row["samples_per_s"] and ceiling else "-"
        lines.append(f"| {row['mode']} | {epg.fmt_m(row['samples_per_s'])} | {ratio} | {ms['iteration_s']} | "
                     f"{ms['phase/collect_s']} | {ms['phase/update_s']} | {ms['phase/idle_s']} |")
    targets = doc["targets"]
    lines += ["", "| mode | seeds | " + " | ".join(f"time to {t} m/s (median; seeds there)" for t in targets)
              + " | samples/s |", "|---|---:|" + "---:|" * (len(targets) + 1)]
    for mode, cell in epg.learning_by_size(doc, key="mode").items():
        lines.append(f"| {mode} | {cell['seeds']} | " + " | ".join(
            f"{epg.time_text(cell[t]['median_s'])} ({cell[t]['reached']}/{cell['seeds']})" for t in targets)
            + f" | {epg.fmt_m(cell['samples_per_s'])} |")
    return "\n".join(lines)


def throughput_row(mode: str, run: dict, args) -> dict:
    """A mode's steady rate and phases; none from a run too short to time (a compiled run's first update
    compiles for seconds, so it needs a longer --throughput-seconds than the others)."""
    s = run["summary"]
    iterations = s.get("iterations") or 0
    row = {"mode": mode, "samples_per_s": s.get("steady_samples_per_s_median"),
           "phase_s": s.get("steady_phase_s_median"), "peak_mib": run["peak_mib"], "iterations": iterations}
    if iterations < epg.MIN_ITERATIONS:
        row.update(samples_per_s=None, phase_s=None,
                   too_short=f"{iterations} iterations in {args.throughput_seconds:g} s: too few to time; "
                             "raise --throughput-seconds")
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True, help="output directory")
    ap.add_argument("--task", default="Ant", choices=sorted(epg.TARGETS))
    ap.add_argument("--envs", type=int, default=epg.BASE_ENVS)
    ap.add_argument("--throughput-seconds", type=float, default=60.0,
                    help="each mode's throughput run, from its process's start (0: none, the learning runs only)")
    ap.add_argument("--seconds", type=float, default=None, help="training time per learning run (Ant 180, Humanoid 240)")
    ap.add_argument("--seeds", type=int, nargs="*", default=[0, 1, 2],
                    help="seeds of the learning runs (none: the throughput runs only)")
    ap.add_argument("--modes", nargs="+", default=["sequential", "overlap"], choices=list(MODES),
                    help="the ways of training to compare, in this order (default: sequential overlap)")
    ap.add_argument("--bench-steps", type=int, default=100)
    ap.add_argument("--batch-size", type=int, default=None, help="the mini-batch (default: the task's)")
    ap.add_argument("--keep-going", action="store_true",
                    help="train every learning run for its whole time (default: stop it once it reaches the last target)")
    ap.add_argument("--device", default=None)
    args = ap.parse_args(argv)
    args.scale_batch = False
    seconds = args.seconds or (180.0 if args.task == "Ant" else 240.0)
    if args.throughput_seconds < 0:
        ap.error(f"--throughput-seconds {args.throughput_seconds}: must be 0 (no throughput runs) or more")
    for flag, v in (("--envs", args.envs), ("--seconds", seconds),
                    ("--bench-steps", args.bench_steps), ("--batch-size", args.batch_size or 1)):
        if not v > 0:
            ap.error(f"{flag} {v}: must be positive")
    if args.batch_size is not None:
        epg.BATCH[args.task] = args.batch_size
    import torch  # noqa: PLC0415

    from warpgym.sim.device import resolve_device  # noqa: PLC0415

    device = resolve_device(args.device)
    name = torch.cuda.get_device_name(torch.device(device)) if device.startswith("cuda") else "cpu"
    os.makedirs(os.path.join(args.out, "runs"), exist_ok=True)
    path = os.path.join(args.out, f"overlap_{args.task}.json")
    doc = {"task": args.task, "device": name, "num_envs": args.envs, "targets": list(epg.TARGETS[args.task]),
           "argv": sys.argv[1:] if argv is None else argv, "modes": list(args.modes), "env_steps_per_s": None,
           "throughput": [], "learning": []}
    doc["env_steps_per_s"] = epg.env_steps(args.task, args.envs, args)
    epg.save(path, doc)
    modes = {m: MODES[m] for m in dict.fromkeys(args.modes)}
    for mode, flags in (modes.items() if args.throughput_seconds else ()):
        run = epg.train(args.task, args.envs, args.throughput_seconds, 0,
                        os.path.join(args.out, "runs", f"{args.task}-{mode}-tp"), args, flags)
        doc["throughput"].append(throughput_row(mode, run, args))
        epg.save(path, doc)
    for seed in args.seeds:
        for mode, flags in modes.items():  # the modes alternate, so a drifting machine touches both alike
            run = epg.train(args.task, args.envs, seconds, seed,
                            os.path.join(args.out, "runs", f"{args.task}-{mode}-s{seed}"), args, flags,
                            stop_at=epg.stop_at(args))
            doc["learning"].append(epg.learning_row(run, args.task, seed, seconds, mode=mode))
            epg.save(path, doc)
    text = tables(doc)
    with open(os.path.join(args.out, f"overlap_{args.task}.md"), "w") as f:
        f.write(text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
