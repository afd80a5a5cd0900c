"""The Ant's and the Humanoid's step, loop by loop, from the JSON ``warpgym bench --robots ... --out JSON`` writes:
each robot's task env against the physics under it (``Sim.step()``, Newton's solver loop, MuJoCo Warp alone), in
env-steps per second, the median of the run's repeats.

    warpgym bench --robots ant humanoid --num-envs 4096 --steps 100 --repeats 5 --out JSON    # on a GPU
    python -m benchmarks.speed.robot_steps --report JSON
"""

from __future__ import annotations

import argparse
import json
import os
import sys

LOOPS = (("env_steps_per_s", "task env"), ("physics_steps_per_s", "`Sim.step()`"),
         ("raw_steps_per_s", "Newton's solver loop"), ("mjwarp_steps_per_s", "MuJoCo Warp alone"))


def table(doc: dict) -> str:
    meta = doc["meta"]
    repeats = sorted({r["repeats"] for r in doc["results"]})
    lines = [f"{meta['gpu']}, warp {meta['warp']}, torch {meta['torch']}: env-steps/s, the median of "
             f"{'/'.join(map(str, repeats))} timings of {doc['results'][0]['steps']} steps", "",
             "| robot | envs | " + " | ".join(name for _, name in LOOPS) + " | task env / MuJoCo Warp |",
             "|---|---:|" + "---:|" * len(LOOPS) + "---:|"]
    for r in doc["results"]:
        cells = " | ".join(f"{r[key] / 1e6:.2f} M" for key, _ in LOOPS)
        lines.append(f"| {r['robot'].capitalize()} | {r['num_envs']} | {cells} | "
                     f"{r['env_steps_per_s'] / r['mjwarp_steps_per_s']:.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--report", required=True, metavar="JSON", help="what `warpgym bench --robots ... --out` wrote")
    args = ap.parse_args(argv)
    if not os.path.isfile(args.report):
        ap.error(f"--report {args.report}: no such file; pass the --out JSON of `warpgym bench --robots ...`")
    with open(args.report) as f:
        doc = json.load(f)
    if not doc.get("results") or "robot" not in doc["results"][0]:
        ap.error(f"--report {args.report}: no robots' rows in it; it is not a `warpgym bench --robots` JSON")
    print(table(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
