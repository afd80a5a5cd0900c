"""The learning table's policies in Gymnasium's v4 of their task beside v5: how far the definitions the
reference figures were made in move a return.

Tianshou's figures come from gym's v3 tasks (v2 for Reacher and the two pendulums) on mujoco-py; Gymnasium's
v4 keeps those definitions on MuJoCo's own bindings, v5 changed some of them (Reacher's distance read after
the step, not before it; Walker2d's right foot at friction 1.9, not 0.9; no survival reward on the step
that falls). This script plays each run's last kept policy by ``warpgym eval --env-version 4``: the same
30 episodes (reset seeds 0, 1000, 2000 and the next nine of each) in both versions, and, where v4's
observation holds v5's, nothing else changed. Ant, Humanoid and HumanoidStandup lay out v4's observation
otherwise and Pusher's v4 needs MuJoCo < 3: they are left out.

    python -m benchmarks.learning.suite_versions --runs OUT [OUT2 ...] --json docs/bench/suite_versions.json
    python -m benchmarks.learning.suite_versions --report docs/bench/suite_versions.json
    python -m benchmarks.learning.suite_versions --runs OUT --update docs/bench/suite_versions.json

``--update JSON`` keeps an earlier table's rows and replaces those of the rows (tasks) the runs have, in place:
a row made again (a preset changed) needs only its own policies, not every earlier run's checkpoints.

``--runs`` takes suite_learning.py's output folders (the ``<task>-seed<k>.json`` and the ``runs/`` beside
them, where the checkpoints are); the policies' own ``.v4.json`` lie beside their checkpoints, and a policy
whose file is there from an earlier run (the same episodes and seeds, newer than the checkpoint) is not
played again: a new row costs the new row's plays.
"""

from __future__ import annotations

import argparse
import glob
import json
import os
import sys
import time


from benchmarks.harness import read_report  # noqa: E402
from benchmarks.learning.suite_learning import SEEDS, made_with, play, row_name, run_stem  # noqa: E402
from benchmarks.targets import REFERENCE, REFERENCE_VERSION  # noqa: E402


def earlier(ckpt: str, episodes: int) -> dict | None:
    """The policy's ``.v4.json`` from an earlier run of this script, where it is newer than the checkpoint and
    played the same episodes from the same reset seeds; else None (delete the file to play it again)."""
    path = ckpt + ".v4.json"
    if not os.path.isfile(path) or os.path.getmtime(path) < os.path.getmtime(ckpt):
        return None
    with open(path) as f:
        r = json.load(f)
    same = r.get("episodes") == episodes * len(SEEDS) and [s["seed"] for s in r.get("v4_per_seed", [])] == list(SEEDS)
    return r | {"seeds": list(SEEDS)} if same and "v4_return" in r else None


def score(folders: list[str], episodes: int, device: str | None) -> list[dict]:
    from warpgym.tasks.suite import SUITE  # noqa: PLC0415

    rows = []
    for folder in folders:
        for path in sorted(glob.glob(os.path.join(folder, "*-seed*.json"))):
            if os.path.basename(path).startswith("sb3-"):
                continue
            run = json.load(open(path))["run"]
            if "error" in run or SUITE[run["task"]].v4_observation is None:
                continue
            last = run["kept"][-1]
            stem = run_stem(run["task"], run["seed"], made_with(run))
            ckpt = os.path.join(folder, "runs", stem, last["checkpoint"])
            if not os.path.exists(ckpt):
                raise SystemExit(f"{path}: its last policy {ckpt} is not there; --runs takes the folder that "
                                 "suite_learning.py --out wrote, runs/ included")
            r = earlier(ckpt, episodes) or play(ckpt, episodes, SEEDS, ckpt + ".v4.json", device,
                                                 extra=("--env-version", "4"))
            # a candidate preset's runs (suite_learning --config) are a row of their own, as in its table
            rows.append({"task": row_name(run), "reference_task": run["task"], "seed": run["seed"],
                         "mark_s": last["mark_s"], "checkpoint": ckpt,
                         "episodes": r["episodes"], "v5_return": r["gymnasium_return"],
                         "v5_length": r["gymnasium_length"],
                         "v4_return": r["v4_return"], "v4_length": r["v4_length"], "v4_over_v5": r["v4_over_v5"],
                         "v5_terms": r["gymnasium_terms"], "v4_terms": r["v4_terms"]})
    return rows


def updated(old: list[dict], new: list[dict]) -> list[dict]:
    """``old`` rows with each row (task) that ``new`` has replaced by ``new``'s, where it stood; new rows last."""
    fresh = {r["task"] for r in new}
    out, placed = [], set()
    for r in old:
        if r["task"] not in fresh:
            out.append(r)
        elif r["task"] not in placed:
            placed.add(r["task"])
            out += [n for n in new if n["task"] == r["task"]]
    return out + [n for n in new if n["task"] not in placed]


def table(rows: list[dict]) -> str:
    out = ["| task | seeds | policy at | v5 return | v4 return | v4 / v5 | the term that moved (v5 -> v4) | "
           "episode length v5 / v4 | reference (its version) |",
           "|---|---:|---:|---:|---:|---:|---|---|---:|"]
    for task in dict.fromkeys(r["task"] for r in rows):
        mine = [r for r in rows if r["task"] == task]
        n = len(mine)

        def mean(key, mine=mine, n=n):
            return sum(r[key] for r in mine) / n

        both = [k for k in mine[0]["v5_terms"] if all(k in r["v4_terms"] for r in mine)]
        terms = {k: sum(r["v4_terms"][k] - r["v5_terms"][k] for r in mine) / n for k in both}
        moved = "- (v4's info names no term)"
        if terms:
            name = max(terms, key=lambda k: abs(terms[k]))
            v5_term = sum(r["v5_terms"][name] for r in mine) / n
            moved = f"{name} {v5_term:.1f} -> {v5_term + terms[name]:.1f}"
        mark = f"{mine[0]['mark_s'] / 60:g} min"
        ref_task = mine[0].get("reference_task", task)  # rows saved before candidate rows existed lack it
        out.append(f"| {task} | {n} | {mark} | {mean('v5_return'):.1f} | {mean('v4_return'):.1f} | "
                   f"{mean('v4_over_v5'):.3f} | {moved} | "
                   f"{mean('v5_length'):.0f} / {mean('v4_length'):.0f} | "
                   f"{REFERENCE[ref_task]:g} ({REFERENCE_VERSION[ref_task]}) |")
    return "\n".join(out)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", nargs="+", metavar="OUT", help="suite_learning.py output folders")
    ap.add_argument("--report", metavar="JSON", help="print the table of an earlier --json")
    ap.add_argument("--json", metavar="JSON", help="write the rows here")
    ap.add_argument("--update", metavar="JSON",
                    help="an earlier --json whose rows these runs' rows replace, row by row (written back to it "
                         "unless --json names another file)")
    ap.add_argument("--eval-episodes", type=int, default=10, help="episodes per reset seed of 3 (default 10)")
    ap.add_argument("--device", default=None)
    args = ap.parse_args(argv)
    if args.report:
        print(table(read_report(args.report, "the file an earlier --json wrote")["rows"]))
        return 0
    if not args.runs:
        ap.error("--runs OUT... (suite_learning.py's output folders) or --report JSON")
    if args.eval_episodes < 1:
        ap.error(f"--eval-episodes {args.eval_episodes}: must be a positive integer, e.g. 10")
    earlier_rows, earlier_meta = None, None
    if args.update:
        what = "the file an earlier --json wrote, e.g. docs/bench/suite_versions.json"
        earlier = read_report(args.update, what, flag="--update")
        if not isinstance(earlier, dict) or not isinstance(earlier.get("rows"), list):
            ap.error(f"--update {args.update}: holds no table of rows; pass {what}")
        earlier_rows, earlier_meta = earlier["rows"], earlier.get("meta")
    rows = score(args.runs, args.eval_episodes, args.device)
    if not rows:
        raise SystemExit(f"--runs {args.runs}: no run of a task that plays in v4 (<task>-seed<k>.json)")
    if earlier_rows is not None:
        rows = updated(earlier_rows, rows)
        args.json = args.json or args.update
    if args.json:
        from warpgym.cli import write_json  # noqa: PLC0415

        meta = {"date": time.strftime("%Y-%m-%d"), "command": " ".join(
            ["python -m benchmarks.learning.suite_versions"] + (argv or sys.argv[1:]))}
        if earlier_meta is not None:
            meta["updated"] = earlier_meta  # how the rows kept from it were made
        write_json(args.json, {"meta": meta, "rows": rows})
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
