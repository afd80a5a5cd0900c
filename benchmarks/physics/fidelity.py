"""Does the physics hold at convergence? Train, keep policies at set times, replay each at a 4x finer
step and in native MuJoCo, and write one table.

    python -m benchmarks.physics.fidelity --out OUT --task Ant --seeds 0 1 --seconds 300 --save-at 60 120
    python -m benchmarks.physics.fidelity --out OUT --task Ant --candidates substeps4 --seeds 0 --seconds 150
    python -m benchmarks.physics.fidelity --out OUT --task Ant --no-train --probes tests/data/ant_flying_policy.pt
    python -m benchmarks.physics.fidelity --out OUT --replay RUN_DIR [RUN_DIR ...]       # runs trained elsewhere, no training
    python -m benchmarks.physics.fidelity --report OUT [OUT ...]                         # the tables again

For each candidate (CANDIDATES: named physics settings; "default" is the task's own) and seed,
scripts/train.py trains --num-envs envs for --seconds of wall-clock time, keeping a checkpoint at each
--save-at mark and at the end. Each kept policy then plays one --steps episode per robot, deterministic:
warpgym at the training step and at --finer times the substeps (--envs robots each, on the GPU when
there is one), and native MuJoCo at both (--native-copies robots each, in CPU processes beside the
warpgym replays). Probes (--probes CKPT ...) are policies trained elsewhere, for example on an
exploitable step; each is replayed with every candidate's physics (or --probe-candidates') in the same
four settings.

Writes OUT/fidelity.json after every run and prints two markdown tables. Policies: forward speed at the
training step, the other settings' speeds as shares of it, torso height, the share of steps with no foot
on the ground and the longest such flight (native MuJoCo, which checks every substep), falls, the
energy the step pays in (native MuJoCo at both steps: the mechanical energy gained beyond the work of
every force, per robot and as a share of the motors'; benchmarks/physics/energy.py), and
whether the policy holds: >= 0.90 at the finer step in both simulators and >= 0.95 in native MuJoCo at
the training step. Runs: steady samples/s, when the training episodes first reached the task's target
speed (Ant 3 m/s, Humanoid 2 m/s), diverged resets, the last evaluation. Probes: the four speeds, and
whether they agree within 10 % or 0.5 m/s, whichever is larger.
"""

from __future__ import annotations

import argparse
import concurrent.futures as futures
import json
import multiprocessing
import os
import subprocess
import sys
import time

from benchmarks.harness import TRAIN, read_summary  # noqa: E402

from benchmarks.targets import WALKING  # noqa: E402

# Named physics settings, each complete for the fields it names (so a later change of the task's
# defaults does not change what a name means). "default" is the task as it stands.
CANDIDATES: dict[str, dict] = {
    "default": {},
    # the task's own physics at 3 substeps: 1/180 s, the timestep nv_humanoid.xml itself declares
    "substeps3": {"substeps": 3},
    # Isaac Gym's step: 2 substeps; 8 solver iterations; nv_ant.xml's armature (0.01)
    "isaac-step": {"substeps": 2, "physics": {"solver_iterations": 8, "ls_iterations": 8, "armature": None}},
    # the Ant's defaults from 2026-11-22 to 2026-11-23: 3 substeps of 4 iterations, nv_ant.xml's armature
    "nov22": {"substeps": 3, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": None}},
    "substeps4": {"substeps": 4, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": None}},
    "armature0.05": {"substeps": 3, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": 0.05}},
    "armature0.1": {"substeps": 3, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": 0.1}},
    # the Humanoid's own step (2 substeps of 8 iterations) with a stiffer rotor on every hinge, against
    # nv_humanoid.xml's 0.006-0.02 kg m^2: the Ant's remedy, probed on Humanoid policies
    "humanoid-armature0.1": {"substeps": 2, "physics": {"solver_iterations": 8, "ls_iterations": 8, "armature": 0.1}},
    "humanoid-armature0.3": {"substeps": 2, "physics": {"solver_iterations": 8, "ls_iterations": 8, "armature": 0.3}},
    # the Humanoid's step until 2026-11-24 (Isaac Gym's 2 substeps, 8 iterations, the MJCF's armature), and
    # 1/180 s steps with 8 or 4 iterations: the finer step that held in 3-minute runs, and its cheaper form
    "humanoid-2x8": {"substeps": 2, "physics": {"solver_iterations": 8, "ls_iterations": 8, "armature": None}},
    "humanoid-3x8": {"substeps": 3, "physics": {"solver_iterations": 8, "ls_iterations": 8, "armature": None}},
    "humanoid-3x4": {"substeps": 3, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": None}},
    # finer still: 1/240 s, and 1/300 s (next to the 0.003 s of MuJoCo's own Humanoid in Gymnasium), for a
    # 1/180 s policy that sprints 17 m/s after 10 minutes and falls at a 4x finer step (seed 1)
    "humanoid-4x4": {"substeps": 4, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": None}},
    "humanoid-5x4": {"substeps": 5, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": None}},
    # today's Humanoid step with the damping implicit Euler underplays at it put back (Physics.exact_damping):
    # seed 1's gait at 5 substeps leans on that underplay (docs/tasks.md)
    "humanoid-3x8-exact-damping": {"substeps": 3, "physics": {"solver_iterations": 8, "ls_iterations": 8,
                                                              "armature": None, "exact_damping": True}},
    # the same at 1/240 s, should 1/180 s still leave the gait a step to lean on
    "humanoid-4x4-exact-damping": {"substeps": 4, "physics": {"solver_iterations": 4, "ls_iterations": 4,
                                                              "armature": None, "exact_damping": True}},
    # MuJoCo's "implicit" integrator (implicitfast plus the velocity derivative of the Coriolis and centrifugal
    # forces): at 1/180 s implicitfast pays a 10-minute seed-1 sprint 1.5 kW of its own (step_sensitivity.py)
    "humanoid-3x8-implicit": {"substeps": 3, "physics": {"integrator": "implicit", "solver_iterations": 8,
                                                         "ls_iterations": 8, "armature": None}},
    "humanoid-2x8-implicit": {"substeps": 2, "physics": {"integrator": "implicit", "solver_iterations": 8,
                                                         "ls_iterations": 8, "armature": None}},
    # the seed-1 gaits swing hinges at 72-105 rad/s, half a radian per 1/180 s substep, where the step's error pays
    # kilowatts in: a motor's top speed, as PhysX clamps articulation joint speeds (25 rad/s: a sprinter's knee)
    "humanoid-3x8-speed25": {"substeps": 3, "physics": {"solver_iterations": 8, "ls_iterations": 8, "armature": None,
                                                        "max_joint_speed": 25.0}},
    # a DC motor's back-EMF instead of an ideal torque source (Physics.motor_speed): torque falls with speed, to 0 at
    # 25 rad/s at the full command; momentum-conserving where the clamp above is not (it paid a 35 m/s gait 13 kW)
    "humanoid-3x8-motor25": {"substeps": 3, "physics": {"solver_iterations": 8, "ls_iterations": 8, "armature": None,
                                                        "motor_speed": 25.0, "exact_damping": True}},
    # the motor without exact_damping: at 1/180 s exact_damping scales the motor's damping by up to 2.3 (hip_z) and
    # at 1/720 s by 1.2, so the motor's top speed gear / damping changed with the step (seed 0 fell at 4x finer);
    # implicit Euler reaches the same top speed at any step. With a rotor (armature 0.1), as a geared motor has,
    # h d / I falls from 1.5 to 0.3 at the worst hinge, where implicit Euler's damping is within 13 % of exact
    "humanoid-3x8-motor25-plain": {"substeps": 3, "physics": {"solver_iterations": 8, "ls_iterations": 8,
                                                              "armature": None, "motor_speed": 25.0}},
    # the Humanoid's default from 2026-11-24 evening: held both seeds at 1, 2, 5 and 10 minutes (T1, T2)
    "humanoid-3x8-motor25-armature0.1": {"substeps": 3, "physics": {"solver_iterations": 8, "ls_iterations": 8,
                                                                    "armature": 0.1, "motor_speed": 25.0}},
    # seed 1's 10-minute gait of the plain motor still takes 287 W from the explicit velocity-product forces, which grow
    # with joint speed (34 rad/s): a slower motor (15 rad/s), or the 25 rad/s motor at 1/240 s
    "humanoid-3x8-motor15-plain": {"substeps": 3, "physics": {"solver_iterations": 8, "ls_iterations": 8,
                                                              "armature": None, "motor_speed": 15.0}},
    "humanoid-4x4-motor25-plain": {"substeps": 4, "physics": {"solver_iterations": 4, "ls_iterations": 4,
                                                              "armature": None, "motor_speed": 25.0}},
    # the Ant's armature at 8 iterations or 4 substeps: for a ratio that falls with training (0.91 at 10 minutes)
    "ant-3x8": {"substeps": 3, "physics": {"solver_iterations": 8, "ls_iterations": 8, "armature": 0.1}},
    "ant-4x4": {"substeps": 4, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": 0.1}},
    # a softer contact than the MJCF's 0.02 s: the step a flying gait is fitted to (tests/data)
    "soft-contact": {"substeps": 3, "physics": {"solver_iterations": 4, "ls_iterations": 4, "armature": None,
                                                "contact_timeconst": 0.04}},
}
HOLDS = {"finer": 0.90, "native": 0.95, "native_finer": 0.90}  # issue 22, item 1


def train_flags(candidate: dict) -> list[str]:
    flags = ["--substeps", str(candidate["substeps"])] if "substeps" in candidate else []
    for name, value in candidate.get("physics", {}).items():
        flags += ["--physics", f"{name}={'none' if value is None else value}"]
    return flags


# ---------------------------------------------------------------- replays
def _native(job: dict) -> dict:
    """One native-MuJoCo replay, in a worker process (CPU only)."""
    os.environ["CUDA_VISIBLE_DEVICES"] = ""
    import torch

    from benchmarks.physics.energy import PowerMeter
    from warpgym.cli import sim2sim
    from agents.checkpoint import load

    torch.set_num_threads(1)
    t0 = time.perf_counter()
    ckpt = load(job["checkpoint"], torch.device("cpu"))
    row = sim2sim.replay_native(ckpt, job["env_args"], job["substeps"], job["copies"], job["steps"], job["seed"],
                                account=PowerMeter)
    return {**row, "wall_s": round(time.perf_counter() - t0, 1)}


def replay_all(policies: list[dict], args, pool) -> None:
    """Fill each policy's ``rows``: warpgym here (at the training step, then --finer), native MuJoCo in
    ``pool`` meanwhile. ``policies`` items: checkpoint, env_args (task, physics), substeps."""
    import torch

    from warpgym.cli import sim2sim
    from agents.checkpoint import load
    from warpgym.sim.device import resolve_device

    device = resolve_device(args.device)
    envs = args.envs or (256 if device.startswith("cuda") else 8)
    pending = []
    for p in policies:
        p["rows"] = {}
        for key, substeps in (("native", p["substeps"]), ("native_finer", p["substeps"] * args.finer)):
            job = {"checkpoint": p["checkpoint"], "env_args": p["env_args"], "substeps": substeps,
                   "copies": args.native_copies, "steps": args.steps, "seed": args.seed}
            pending.append((p, key, substeps, pool.submit(_native, job)))
    for p in policies:
        ckpt = load(p["checkpoint"], torch.device(device))
        for key, substeps in (("warpgym", p["substeps"]), ("finer", p["substeps"] * args.finer)):
            t0 = time.perf_counter()
            row = sim2sim.replay_warpgym(ckpt, p["env_args"], substeps, envs, args.steps, device, args.seed)
            p["rows"][key] = {**row, "substeps": substeps, "wall_s": round(time.perf_counter() - t0, 1)}
    for p, key, substeps, fut in pending:
        p["rows"][key] = {**fut.result(), "substeps": substeps}
    for p in policies:
        base = p["rows"]["warpgym"]["forward_speed"]
        for row in p["rows"].values():
            row["speed_ratio"] = row["forward_speed"] / base if base else float("nan")
        r = p["rows"]
        p["holds"] = (r["finer"]["speed_ratio"] >= HOLDS["finer"] and r["native"]["speed_ratio"] >= HOLDS["native"]
                      and r["native_finer"]["speed_ratio"] >= HOLDS["native_finer"])
        speeds = [r[k]["forward_speed"] for k in ("warpgym", "finer", "native", "native_finer")]
        p["agree"] = max(speeds) - min(speeds) <= max(0.1 * max(abs(s) for s in speeds), 0.5)


# ---------------------------------------------------------------- runs
def kept_policies(run_dir: str, facts: dict, marks: list[float]) -> list[dict]:
    """The run's checkpoints kept at its --save-at marks, and its last one. A run trained without
    --save-at but with --keep-checkpoints gives, for each of ``marks``, its first checkpoint after it."""
    import torch

    from agents.checkpoint import load
    from agents.logger import read_metrics

    # by name in the run directory: the run may have been trained on another machine and moved here
    out = [{"label": f"{k['mark_s']:g} s", "checkpoint": os.path.join(run_dir, os.path.basename(k["path"])),
            "iteration": k["iteration"], "time_s": k["time_s"]} for k in facts["kept_checkpoints"]]
    if not out and marks:
        times = {r["iteration"]: r["time_s"] for r in read_metrics(run_dir)}
        saved = sorted(int(f[11:-3]) for f in os.listdir(run_dir) if f.startswith("checkpoint-") and f.endswith(".pt"))
        for mark in marks:
            it = next((i for i in saved if times.get(i, -1.0) >= mark), None)
            if it is not None and all(p["iteration"] != it for p in out):
                out.append({"label": f"{mark:g} s", "checkpoint": os.path.join(run_dir, f"checkpoint-{it}.pt"),
                            "iteration": it, "time_s": times[it]})
    final = os.path.join(run_dir, "checkpoint.pt")
    last = load(final, torch.device("cpu"))
    if not out or out[-1]["iteration"] != last["iteration"]:
        out.append({"label": "end", "checkpoint": final, "iteration": last["iteration"],
                    "time_s": round(last["elapsed_s"], 3)})
    env_args = last["config"]["env_args"]
    for p in out:
        p["env_args"] = {"task": env_args["task"], "physics": env_args.get("physics") or {}}
        p["substeps"] = env_args.get("substeps") or _task(env_args["task"]).substeps
    return out


def candidate_label(run: dict) -> str:
    """The run's candidate name, marked when its physics is the task's default today."""
    from warpgym.sim.physics import Physics

    task, p = _task(run["task"]), run["policies"][0]
    try:
        today = p["substeps"] == task.substeps and Physics.from_dict(p["env_args"]["physics"]) == task.physics
    except ValueError:  # a setting this code no longer knows
        today = False
    if run["candidate"] == "default":  # "default" names different physics as the defaults change: say which
        return f"default ({p['substeps']} substeps x {p['env_args']['physics'].get('solver_iterations', '?')})"
    return f"{run['candidate']} (today's default)" if today else run["candidate"]


def _task(name: str):
    from warpgym.tasks.robots import get_task

    return get_task(name)


def run_facts(run_dir: str) -> dict:
    """What a run's summary.json says about cost and learning."""
    from agents.logger import first_reaching, read_metrics

    s = read_summary(run_dir)
    with open(os.path.join(run_dir, "config.json")) as f:
        task = json.load(f)["task"]
    rows = read_metrics(run_dir)
    evals = [r for r in rows if "eval/return" in r]
    target = WALKING.get(task)
    return {"task": task, "device": s.get("device"), "num_envs": s.get("num_envs"), "iterations": s.get("iterations"),
            "samples_per_s": s.get("steady_samples_per_s_median"), "first_iteration_s": s.get("first_iteration_time_s"),
            "target_speed": target, "first_at_target": first_reaching(rows, "speed", target) if target else None,
            "faults": s.get("faults"), "final": s.get("final"), "startup": s.get("startup", {}).get("timeline"),
            "last_eval": {k: evals[-1][k] for k in ("time_s", "samples", "eval/return", "eval/speed")} if evals else None,
            "kept_checkpoints": s.get("kept_checkpoints", [])}


def train(task: str, name: str, seed: int, args) -> str:
    run_dir = os.path.join(args.out, "runs", f"{task}-{name}-s{seed}")
    cmd = [*TRAIN, "--task", task, "--seed", str(seed), "--time-limit",
           str(args.seconds), "--eval-gap", "20", "--no-plots", "--run-dir", run_dir,
           *(["--num-envs", str(args.num_envs)] if args.num_envs else []),
           *(["--device", args.device] if args.device else []),
           *(["--save-at", *map(str, args.save_at)] if args.save_at else []), *train_flags(CANDIDATES[name])]
    with open(run_dir + ".train.log", "w") as log:
        rc = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT, timeout=args.seconds + 600).returncode
    if rc != 0:
        raise RuntimeError(f"train.py exited {rc}: see {run_dir}.train.log")
    return run_dir


def save(out: str, doc: dict) -> None:
    from warpgym.cli import write_json

    write_json(os.path.join(out, "fidelity.json"), doc)


# ---------------------------------------------------------------- tables
def paid_in(row: dict) -> str:
    """The energy the integrator added per robot, and its share of the motors' (replays made before the
    account existed: -)."""
    power = row.get("power_w")
    if not power:
        return "-"
    share = f" ({100 * power['integrator'] / power['motors']:.0f} %)" if power["motors"] > 0 else ""
    return f"{power['integrator']:.0f} W{share}"


def tables(doc: dict, marks: list[str] | None = None) -> str:
    """The replays' table (only the policies kept at ``marks``, "120 s" or "end", where given) and the runs'."""
    lines = ["| task | candidate | seed | policy | speed at the step | 4x finer | native | native 4x finer | "
             "torso height | no foot on ground (native) | longest flight (native) | falls (warpgym) | "
             "paid in by the step (native, at the step / 4x finer) | holds |",
             "|---|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"]
    for run in doc.get("runs", []):
        for p in run["policies"]:
            if marks and p["label"] not in marks:
                continue
            r = p["rows"]
            lines.append(
                f"| {run['task']} | {candidate_label(run)} | {'-' if run['seed'] is None else run['seed']} | {p['label']} (it {p['iteration']}) | "
                f"{r['warpgym']['forward_speed']:.2f} m/s | {r['finer']['speed_ratio']:.2f} | "
                f"{r['native']['speed_ratio']:.2f} | {r['native_finer']['speed_ratio']:.2f} | "
                f"{r['warpgym']['torso_height']:.2f} m | {100 * r['native']['no_foot_contact_share']:.0f} % | "
                f"{r['native']['longest_airborne_steps']:.0f} steps | {r['warpgym']['falls']}/{r['warpgym']['robots']} | "
                f"{paid_in(r['native'])} / {paid_in(r['native_finer'])} | {'yes' if p['holds'] else '**no**'} |")
    lines += ["", "| task | candidate | seed | device | samples/s | first iteration | training episodes at target speed | "
              "diverged resets | last evaluation |", "|---|---|---:|---|---:|---:|---:|---:|---:|"]
    for run in doc.get("runs", []):
        f = run["facts"]
        hit = f["first_at_target"]
        ev = f["last_eval"]
        lines.append(
            f"| {run['task']} | {candidate_label(run)} | {'-' if run['seed'] is None else run['seed']} | {f['device']} | {f['samples_per_s'] / 1e6:.2f} M | "
            f"{f['first_iteration_s']:.1f} s | "
            + (f"{f['target_speed']:g} m/s at {hit['time_s']:.1f} s ({hit['samples'] / 1e6:.1f} M)" if hit else "not reached")
            + f" | {(f['faults'] or {}).get('diverged_resets', '-')} | "
            + (f"{ev['eval/return']:.0f} @ {ev['eval/speed']:.2f} m/s ({ev['time_s']:.0f} s)" if ev else "-") + " |")
    if doc.get("probes"):
        lines += ["", "| probe | replayed with | at the step | 4x finer | native | native 4x finer | agree |",
                  "|---|---|---:|---:|---:|---:|---|"]
        for p in doc["probes"]:
            r = p["rows"]
            lines.append(f"| {p['label']} | {p['candidate']} ({p['substeps']} substeps) | "
                         + " | ".join(f"{r[k]['forward_speed']:.2f} m/s" for k in ("warpgym", "finer", "native", "native_finer"))
                         + f" | {'yes' if p['agree'] else '**no**'} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="output directory")
    ap.add_argument("--task", default="Ant")
    ap.add_argument("--candidates", nargs="+", default=["default"], choices=sorted(CANDIDATES))
    ap.add_argument("--seeds", type=int, nargs="+", default=[0])
    ap.add_argument("--seconds", type=float, default=300.0, help="training wall-clock time per run")
    ap.add_argument("--save-at", type=float, nargs="*", default=[60.0, 120.0],
                    help="keep the policies of these seconds since start too (default 60 120)")
    ap.add_argument("--num-envs", type=int, default=None, help="training envs (train.py's default: 8192 Ants or 4096 Humanoids on a GPU)")
    ap.add_argument("--no-train", action="store_true", help="replay --probes / --replay only")
    ap.add_argument("--replay", nargs="+", default=[], metavar="RUN_DIR",
                    help="replay runs trained elsewhere (and train nothing)")
    ap.add_argument("--probes", nargs="+", default=[], metavar="CKPT", help="replay these with every candidate")
    ap.add_argument("--probe-candidates", nargs="+", default=None, choices=sorted(CANDIDATES),
                    help="the physics the probes are replayed with (default: --candidates)")
    ap.add_argument("--envs", type=int, default=None, help="warpgym robots per replay (default 256 GPU, 8 CPU)")
    ap.add_argument("--native-copies", type=int, default=64,
                    help="native MuJoCo robots per replay (32 gave a spread of about 3 %%)")
    ap.add_argument("--steps", type=int, default=1000, help="control steps per replay (one episode)")
    ap.add_argument("--finer", type=int, default=4)
    ap.add_argument("--seed", type=int, default=7, help="seed of the replays' start states")
    ap.add_argument("--device", default=None)
    ap.add_argument("--workers", type=int, default=None, help="native MuJoCo processes (default: cores - 2)")
    ap.add_argument("--report", nargs="+", metavar="OUT", help="print the tables of these outputs")
    ap.add_argument("--marks", nargs="+", default=None, metavar="MARK",
                    help="with --report: only the policies kept at these marks, seconds or 'end' (e.g. 120 end)")
    args = ap.parse_args(argv)
    marks = None
    if args.marks:
        try:
            marks = [m if m == "end" else f"{float(m):g} s" for m in args.marks]
        except ValueError:
            ap.error(f"--marks {' '.join(args.marks)}: each is a number of seconds or 'end', e.g. --marks 120 end")
    if args.report:
        doc = {"runs": [], "probes": []}
        for out in args.report:
            if not os.path.isfile(out if out.endswith(".json") else os.path.join(out, "fidelity.json")):
                ap.error(f"--report {out}: no fidelity.json there; pass an --out directory of an earlier run")
            with open(out if out.endswith(".json") else os.path.join(out, "fidelity.json")) as f:
                part = json.load(f)
            doc["runs"] += part.get("runs", [])
            doc["probes"] += part.get("probes", [])
        print(tables(doc, marks))
        return 0
    if not args.out:
        ap.error("--out is required (or --report)")
    for name in ("seconds", "native_copies", "steps", "finer"):
        if not getattr(args, name) > 0:
            ap.error(f"--{name.replace('_', '-')} {getattr(args, name)}: must be positive")
    for path in args.probes:
        if not os.path.isfile(path):
            ap.error(f"--probes {path}: no such checkpoint file")
    for path in args.replay:
        if not os.path.isfile(os.path.join(path, "summary.json")):
            ap.error(f"--replay {path}: not a finished run directory (no summary.json); pass one written by train.py")
    os.makedirs(os.path.join(args.out, "runs"), exist_ok=True)
    doc = {"task": args.task, "argv": sys.argv[1:] if argv is None else list(argv), "runs": [], "probes": []}
    workers = args.workers or max(1, (os.cpu_count() or 2) - 2)
    ctx = multiprocessing.get_context("spawn")  # no CUDA context inherited from this process
    with futures.ProcessPoolExecutor(workers, mp_context=ctx) as pool:

        def add_run(candidate: str, seed: int | None, run_dir: str) -> None:
            facts = run_facts(run_dir)
            policies = kept_policies(run_dir, facts, args.save_at)
            replay_all(policies, args, pool)  # done before the next training: no CPU shared with it
            doc["runs"].append({"task": facts["task"], "candidate": candidate, "seed": seed, "run_dir": run_dir,
                                "facts": facts, "policies": policies})
            save(args.out, doc)

        training = not (args.no_train or args.replay)
        for name, seed in [(n, sd) for n in args.candidates for sd in args.seeds] if training else []:
            t0 = time.time()
            run_dir = train(args.task, name, seed, args)
            print(f"trained {args.task} {name} seed {seed} in {time.time() - t0:.0f} s", flush=True)
            add_run(name, seed, run_dir)
        for path in args.replay:
            add_run(os.path.basename(os.path.normpath(path)), None, path)
        for name in (args.probe_candidates or args.candidates) if args.probes else []:
            cand = CANDIDATES[name]
            probes = [{"label": os.path.basename(path), "candidate": name, "checkpoint": path,
                       "env_args": {"task": args.task, "physics": cand.get("physics", {})},
                       "substeps": cand.get("substeps") or _task(args.task).substeps} for path in args.probes]
            replay_all(probes, args, pool)
            doc["probes"] += probes
            save(args.out, doc)
    print(tables(doc))
    return 0


if __name__ == "__main__":
    sys.exit(main())
