"""A trained legged policy's return in mjlab's own env beside warpgym's, on the CPU.

Both envs as they train (observation noise, pushes, startup randomisation and command resampling on), the
checkpoint's mean action, each world's first episode from a reset: its return (the sum of the env's rewards),
length and whether it fell. The two envs draw their own random numbers, so the figure is the ratio of two means
over ``--num-envs`` episodes each, with each mean's standard error; mjlab's side runs in its own interpreter
(benchmarks/physics/mjlab_side.py ``returns``), at the same time as warpgym's.

    python -m benchmarks.physics.legged_returns RUN --mjlab-python .venv-mjlab/bin/python --num-envs 64 --out OUT.json
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

from benchmarks.harness import ROOT, write_json
from benchmarks.physics.first_episodes import first_episodes


def warpgym_returns(ckpt: dict, num_envs: int, seed: int) -> dict:
    """The same protocol as mjlab_side's ``returns`` in warpgym's env (its defaults: the training env)."""
    import torch  # noqa: PLC0415

    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.envs.legged import LeggedVecEnv  # noqa: PLC0415
    from warpgym.tasks.legged import trained_legged_task  # noqa: PLC0415

    task = trained_legged_task(ckpt["config"]["env_args"])
    spec = ckpt["spec"]
    policy, normalize = policy_from_checkpoint(ckpt, spec["num_obs"], spec["num_actions"], torch.device("cpu"))
    env = LeggedVecEnv(task, num_envs=num_envs, device="cpu", seed=seed)
    obs, _ = env.reset(seed=seed)
    episodes = first_episodes(env.step, lambda o: policy.act_deterministic(normalize(o)), obs, num_envs,
                              task.episode_length)
    env.close()
    return {"framework": "warpgym"} | episodes


def stats(side: dict) -> dict:
    r = side["returns"]
    return {"mean": statistics.fmean(r), "sem": statistics.stdev(r) / len(r) ** 0.5, "episodes": len(r),
            "fell": sum(side["fell"]), "mean_length": statistics.fmean(side["lengths"])}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", help="a legged run's folder or checkpoint file")
    ap.add_argument("--mjlab-python", required=True, help="the interpreter that imports mjlab 1.6 (its own venv)")
    ap.add_argument("--num-envs", type=int, default=64, help="worlds, one episode each, in either env")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", help="JSON of both sides' episodes and the ratio")
    args = ap.parse_args(argv)

    import torch  # noqa: PLC0415

    from agents.checkpoint import load_for_command  # noqa: PLC0415

    path, ckpt = load_for_command(args.checkpoint, torch.device("cpu"))
    task = ckpt["config"]["env_args"]["task"]
    with tempfile.TemporaryDirectory() as tmp:
        theirs_json = os.path.join(tmp, "mjlab.json")
        cmd = [args.mjlab_python, "-m", "benchmarks.physics.mjlab_side", "returns", os.path.abspath(path), theirs_json,
               "--task", task, "--num-envs", str(args.num_envs), "--seed", str(args.seed)]
        env = dict(os.environ, PYTHONPATH=ROOT, MUJOCO_GL="disable")
        log = open(os.path.join(tmp, "mjlab.log"), "w")
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env)
        ours = warpgym_returns(ckpt, args.num_envs, args.seed)
        if proc.wait() != 0:
            log.close()
            with open(os.path.join(tmp, "mjlab.log")) as f:
                sys.stderr.write(f.read()[-3000:])
            raise SystemExit(f"error: mjlab's side exited {proc.returncode}: {' '.join(cmd)}")
        with open(theirs_json) as f:
            theirs = json.load(f)
    a, b = stats(ours), stats(theirs)
    ratio = b["mean"] / a["mean"]
    print(f"{task}, {path}: {args.num_envs} first episodes in each env, the policy's mean action")
    print("| env | return (mean ± s.e.) | mean length [steps] | fell |\n|---|---|---|---|")
    for name, s in (("warpgym", a), ("mjlab 1.6", b)):
        print(f"| {name} | {s['mean']:.2f} ± {s['sem']:.2f} | {s['mean_length']:.0f} | {s['fell']} of {s['episodes']} |")
    print(f"mjlab / warpgym: {ratio:.3f} (goal: within 5 %, {'met' if abs(ratio - 1) <= 0.05 else 'not met'})")
    if args.out:
        write_json(args.out, {"task": task, "checkpoint": path, "num_envs": args.num_envs, "seed": args.seed,
                              "warpgym": a | ours, "mjlab": b | theirs, "ratio": ratio})
    return 0


if __name__ == "__main__":
    sys.exit(main())
