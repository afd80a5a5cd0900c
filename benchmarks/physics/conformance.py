"""warpgym's suite against Gymnasium's own envs, the table of docs/tasks.md ("Gymnasium's MuJoCo suite"):
per task, the largest differences of one env step from the same states (Gymnasium's reset states and
states along random-action episodes), and two-sample Kolmogorov-Smirnov tests of the return and
length of whole random-action episodes. Runs on the CPU (Warp's CPU backend, float32, against
Gymnasium's float64 MuJoCo).

    python -m benchmarks.physics.conformance --out docs/bench/conformance.json        # all eleven tasks
    python -m benchmarks.physics.conformance --report docs/bench/conformance.json     # the table again
"""

from __future__ import annotations

import argparse
import json
import sys
import time

from benchmarks.harness import read_report


def measure(name: str, samples: dict, episodes: int, seed: int) -> dict:
    from warpgym.native.suite import (  # noqa: PLC0415
        compare_steps,
        gymnasium_episodes,
        gymnasium_samples,
        ks_two_sample,
        warpgym_episodes,
    )
    from warpgym.envs.suite import SuiteVecEnv  # noqa: PLC0415
    from warpgym.tasks.suite import SUITE  # noqa: PLC0415

    task = SUITE[name]
    start = time.perf_counter()
    steps = gymnasium_samples(task, seed=seed, **samples)
    gaps = compare_steps(SuiteVecEnv(task, num_envs=len(steps), device="cpu", seed=seed), steps)
    returns, lengths = gymnasium_episodes(task, episodes, seed=seed)
    mine_r, mine_l = warpgym_episodes(SuiteVecEnv(task, num_envs=episodes, device="cpu", seed=seed), seed=seed)
    ks_r, ks_l = ks_two_sample(returns, mine_r), ks_two_sample(lengths, mine_l)
    contact = 78 if task.reset_com else 0  # the humanoids: contacts solved by Newton where the file asks for PGS
    body = gaps.obs_by_entry[: len(gaps.obs_by_entry) - contact]
    return {"task": name, "step_samples": gaps.samples, "obs_gap": float(body.max()),
            "contact_obs_gap": float(gaps.obs_by_entry[-contact:].max()) if contact else None,
            "reward_gap": float(gaps.reward), "term_gap": max(gaps.terms.values()) if gaps.terms else 0.0,
            "terminated_mismatches": gaps.terminated_mismatches, "episodes": episodes,
            "gym_return": [float(returns.mean()), float(returns.std())],
            "warpgym_return": [float(mine_r.mean()), float(mine_r.std())],
            "gym_length": float(lengths.mean()), "warpgym_length": float(mine_l.mean()),
            "ks_return": list(ks_r), "ks_length": list(ks_l), "seconds": time.perf_counter() - start}


def table(rows: list[dict]) -> str:
    lines = ["| task | step samples | obs | obs: contact forces | reward | reward terms | terminated differs | "
             "episodes | return: Gymnasium | return: warpgym | KS p (return) | length: Gymnasium | "
             "length: warpgym | KS p (length) |", "|---" * 14 + "|"]
    for r in rows:
        contact = f"{r['contact_obs_gap']:.1e}" if r["contact_obs_gap"] is not None else "-"
        lines.append(
            f"| {r['task']} | {r['step_samples']} | {r['obs_gap']:.1e} | {contact} | {r['reward_gap']:.1e} | "
            f"{r['term_gap']:.1e} | {r['terminated_mismatches']} | {r['episodes']} | "
            f"{r['gym_return'][0]:.1f} ± {r['gym_return'][1]:.1f} | {r['warpgym_return'][0]:.1f} ± "
            f"{r['warpgym_return'][1]:.1f} | {r['ks_return'][1]:.2f} | {r['gym_length']:.1f} | "
            f"{r['warpgym_length']:.1f} | {r['ks_length'][1]:.2f} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="JSON file to write")
    ap.add_argument("--report", metavar="JSON")
    ap.add_argument("--tasks", nargs="+", default=None)
    ap.add_argument("--episodes", type=int, default=64, help="random-action episodes per side and task")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if args.report:
        data = read_report(args.report, "the JSON an earlier --out wrote")
        print(f"{data['meta']['date']}, {data['meta']['command']}")
        print(table(data["rows"]))
        return 0
    if not args.out:
        ap.error("--out OUT.json is required (or --report JSON)")
    if args.episodes < 8:
        ap.error(f"--episodes {args.episodes}: a distribution test needs at least 8, e.g. --episodes 64")
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.tasks.registry import task_names  # noqa: PLC0415

    tasks = args.tasks or task_names("suite")
    unknown = [t for t in tasks if t not in task_names("suite")]
    if unknown:
        ap.error(f"--tasks {unknown}: choose from {task_names('suite')}")
    import gymnasium  # noqa: PLC0415
    import mujoco  # noqa: PLC0415

    samples = dict(episodes=16, steps_apart=5, per_episode=8)
    meta = {"date": time.strftime("%Y-%m-%d"), "gymnasium": gymnasium.__version__, "mujoco": mujoco.__version__,
            "step_samples": samples, "command": " ".join(["python -m benchmarks.physics.conformance"] + (argv or sys.argv[1:]))}
    rows = []
    for name in tasks:
        rows.append(measure(name, samples, args.episodes, args.seed))
        print(json.dumps(rows[-1]), flush=True)
        write_json(args.out, {"meta": meta, "rows": rows})
    print(table(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
