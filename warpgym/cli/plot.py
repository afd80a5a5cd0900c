"""Draw several training runs on one pair of figures: reward against time and against samples.

    warpgym plot runs/Ant-a runs/Ant-b --labels "4096 envs" "16384 envs" --out docs/figures/ant
"""

from __future__ import annotations

import os
import sys

from agents.plotting import plot_runs
from warpgym.cli.flags import CommandParser


def parser() -> CommandParser:
    ap = CommandParser(prog="warpgym plot", description=__doc__)
    ap.add_argument("runs", nargs="+", help="run directories written by warpgym train")
    ap.add_argument("--labels", nargs="+", default=None)
    ap.add_argument("--out", default=".", help="folder for reward_vs_time.png and reward_vs_samples.png")
    ap.add_argument("--title", default="")
    return ap


def main(argv=None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    if args.labels is not None and len(args.labels) != len(args.runs):
        ap.error(f"--labels has {len(args.labels)} entries for {len(args.runs)} runs: give one per run")
    for run in args.runs:
        if not os.path.isfile(os.path.join(run, "metrics.jsonl")):
            ap.error(f"no metrics.jsonl in {run}: pass a run directory written by warpgym train")
    try:
        paths = plot_runs(args.runs, args.out, args.labels, args.title)
    except (FileNotFoundError, ValueError) as e:  # a run directory that is not one, or a damaged metrics file
        raise SystemExit(f"error: {e}") from None
    except ImportError as e:
        raise SystemExit(f"error: plotting needs matplotlib ({e.name} is missing): pip install \"warpgym[train]\"") from None
    for path in paths:
        print("wrote", path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
