"""What does a trained gait lean on? Replay policies in native MuJoCo under changed settings (a finer
step, another integrator, less friction, heavier bodies, more or less joint damping) and account for
the energy each time.

    python -m benchmarks.physics.step_sensitivity tests/data/humanoid_5x4_seed1_policy.pt --out OUT.json
    python -m benchmarks.physics.step_sensitivity CKPT --settings substeps=10 "substeps=10,damping=0.8" \\
        "damping[abdomen|hip_x|hip_y]=1.3" friction=0.8 mass=1.05
    python -m benchmarks.physics.step_sensitivity CKPT1 CKPT2 --settings finer=4 integrator=implicit --no-joints

Each setting is comma-separated NAME=VALUE:
  substeps      per control step (default: the policy's own); finer=K: K times the policy's own
  integrator    euler, implicitfast, implicit or rk4 (MuJoCo's own), to tell a step's error from the model's
  friction, mass  factors on every geom's sliding friction, every body's mass and inertia
  damping       a factor on every hinge's damping; damping[a|b]: on the hinges whose names contain a or b
  match_damping S: each hinge's damping scaled so that implicit Euler damps it per second as at S
                substeps (from the joint's effective inertia, floating base included, at the start pose)
  timeconst     every contact's solref time constant [s]
  iterations    the solver's and line search's iteration caps
  joint_speed   a clamp on every hinge's speed after each substep (Physics.max_joint_speed) [rad/s]
The policy's own settings come first as the reference. Each row: forward speed (frozen at a robot's
fall), falls, and the mean power per robot until its fall [W] of the motors, joint damping, contacts
and joint limits, each force times the substep's mean velocity, integrated over every substep; and
the integrator's: what the mechanical energy gained beyond all of those, the step's own error (0 in
the continuous model; positive: the step pays energy in). Before the rows, each hinge's x = h d / I at
the policy's step (how far implicit Euler's damping falls short). CPU only; a few seconds per setting
for 4 robots and 1000 steps.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import time

import numpy as np


DEFAULT_SETTINGS = ["substeps=6", "substeps=7", "substeps=8", "substeps=10", "friction=0.8", "mass=1.05",
                    "damping[abdomen|hip_x|hip_y]=1.3", "damping[hip_z]=1.3", "damping[ankle]=1.3",
                    "damping[shoulder|elbow]=1.3", "substeps=10,damping=0.8", "substeps=10,match_damping=5",
                    "substeps=20,match_damping=5"]
NAMES = "substeps|finer|friction|mass|damping|match_damping|timeconst|iterations|joint_speed"
SETTING = re.compile(rf"^({NAMES})(\[[\w|]+\])?=([0-9.eE+-]+)$")
NATIVE_INTEGRATORS = ("euler", "implicitfast", "implicit", "rk4")


def parse_setting(text: str) -> dict:
    """'substeps=10,damping[hip_z]=1.3' -> {'substeps': 10, 'damping': [('hip_z',), 1.3]}; a clear error else."""
    out: dict = {"label": text}
    for part in filter(None, text.split(",")):
        if part.strip().startswith("integrator="):
            out["integrator"] = part.strip().split("=", 1)[1]
            if out["integrator"] not in NATIVE_INTEGRATORS:
                raise ValueError(f"setting {part!r}: choose an integrator from {list(NATIVE_INTEGRATORS)}")
            continue
        m = SETTING.match(part.strip())
        if not m:
            raise ValueError(f"setting {part!r} in {text!r}: expected NAME=VALUE with NAME one of "
                             f"{NAMES.replace('|', ', ')}, damping[name|name]=F, or integrator=NAME")
        name, joints, value = m.group(1), m.group(2), float(m.group(3))
        if not value > 0:
            raise ValueError(f"setting {part!r}: the value must be positive")
        if name in ("substeps", "match_damping", "iterations", "finer"):
            out[name] = int(value)
        elif name == "damping":
            out.setdefault("damping", []).append((tuple(joints[1:-1].split("|")) if joints else (), value))
        else:
            out[name] = value
    return out


def match_damping(robot, substeps: int) -> None:
    """Scale each hinge's damping d so that implicit Euler at this model's step h damps a joint per
    second as it does at ``task.dt / substeps``: a step of h keeps 1 / (1 + h d / I) of the speed
    (I from ``hinge_inverse_inertia``), so the damping per second is ln(1 + h d / I) / h."""
    import mujoco  # noqa: PLC0415

    from warpgym.sim.physics import hinge_inverse_inertia  # noqa: PLC0415

    m = robot.model
    dofs, inverse = hinge_inverse_inertia(mujoco, m)
    h, h_ref = m.opt.timestep, robot.task.dt / substeps
    rate = np.log1p(h_ref * m.dof_damping[dofs] * inverse) / h_ref  # per second, times I
    m.dof_damping[dofs] = np.expm1(rate * h) / (h * inverse)  # ln(1 + h d' / I) / h = rate


def replay(ckpt, task, setting: dict, substeps: int, copies: int, steps: int, seed: int) -> dict:
    """One episode per robot with ``setting`` applied (``warpgym.cli.sim2sim.play_native``: a robot is
    no longer stepped after its fall), with the power of each force until the falls."""
    import mujoco  # noqa: PLC0415
    import torch  # noqa: PLC0415

    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.cli.sim2sim import play_native  # noqa: PLC0415
    from benchmarks.physics.energy import PowerMeter  # noqa: PLC0415
    from warpgym.native.robots import NativeRobot  # noqa: PLC0415

    substeps = setting.get("substeps", setting.get("finer", 1) * substeps)
    if "joint_speed" in setting:
        task = task.replace(physics=task.physics.replace(max_joint_speed=setting["joint_speed"]))
    robot = NativeRobot(task, substeps=substeps, copies=copies)
    m = robot.model
    m.geom_friction[:, 0] *= setting.get("friction", 1.0)
    m.body_mass[:] *= setting.get("mass", 1.0)
    m.body_inertia[:] *= setting.get("mass", 1.0)
    if "match_damping" in setting:
        match_damping(robot, setting["match_damping"])
    if "timeconst" in setting:
        m.geom_solref[:, 0] = setting["timeconst"]
    if "iterations" in setting:
        m.opt.iterations = m.opt.ls_iterations = setting["iterations"]
    if "integrator" in setting:
        m.opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{setting['integrator'].upper()}")
    for names, factor in setting.get("damping", []):
        for joint, adr in zip(robot.dof_names, robot.dof_adr):
            if not names or any(n in joint for n in names):
                m.dof_damping[adr] *= factor
    num_obs = task.observation_size(len(robot.dof_names), len(robot.feet))
    policy, normalize = policy_from_checkpoint(ckpt, num_obs, len(robot.dof_names), torch.device("cpu"))
    robot.on_substep = meter = PowerMeter(m)
    row = play_native(robot, lambda obs: policy.act_deterministic(normalize(obs)), steps, seed)
    return {"setting": setting["label"], "substeps": substeps, "forward_speed": row["forward_speed"],
            "falls": row["falls"], "robots": copies, "power_w": meter.watts()}


def joint_table(task, substeps: int) -> list[dict]:
    """Each damped hinge at the policy's step: damping d, effective inertia I, x = h d / I (how far
    implicit Euler's damping falls short: it damps ln(1 + x) / x of the continuous rate)."""
    import mujoco  # noqa: PLC0415

    from warpgym.native.robots import NativeRobot  # noqa: PLC0415
    from warpgym.sim.physics import hinge_inverse_inertia  # noqa: PLC0415

    robot = NativeRobot(task, substeps=substeps)
    m = robot.model
    dofs, inverse = hinge_inverse_inertia(mujoco, m)
    names = {int(a): n for n, a in zip(robot.dof_names, robot.dof_adr)}
    return [{"joint": names[int(dof)], "damping": float(m.dof_damping[dof]), "inertia": round(1 / inv, 4),
             "x": round(m.opt.timestep * m.dof_damping[dof] * inv, 3)} for dof, inv in zip(dofs, inverse)]


def sensitivity(path: str, settings: list[dict], args) -> dict:
    """One checkpoint: its joint table and a row per setting, printed as they come."""
    import torch  # noqa: PLC0415

    from agents.checkpoint import load  # noqa: PLC0415
    from warpgym.tasks.robots import trained_task  # noqa: PLC0415

    ckpt = load(path, torch.device("cpu"))
    env_args = ckpt["config"]["env_args"]
    task = trained_task(env_args)
    substeps = task.substeps
    print(f"## {path}: {env_args['task']}, {substeps} substeps, {task.physics}\n")
    joints = joint_table(task, substeps)
    if args.joints:
        print("| joint | damping | effective inertia | x = h d / I |\n|---|---:|---:|---:|")
        for j in joints:
            print(f"| {j['joint']} | {j['damping']:g} | {j['inertia']:.4f} kg m^2 | {j['x']:.3f} |")
        print()
    rows = []
    print("| setting | substeps | speed | falls | motors | damping | contacts | limits | integrator | wall |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for setting in settings:
        t0 = time.perf_counter()
        row = replay(ckpt, task, setting, substeps, args.copies, args.steps, args.seed)
        row["wall_s"] = round(time.perf_counter() - t0, 1)
        rows.append(row)
        p = row["power_w"]
        print(f"| {row['setting']} | {row['substeps']} | {row['forward_speed']:.2f} m/s | {row['falls']}/{row['robots']} "
              f"| {p['motors']:.0f} W | {p['damping']:.0f} W | {p['contacts']:.0f} W | {p['limits']:.0f} W "
              f"| {p['integrator']:.0f} W | {row['wall_s']} s |", flush=True)
    print()
    return {"checkpoint": path, "task": env_args["task"], "trained_substeps": substeps,
            "physics": task.physics.to_dict(), "joints": joints, "rows": rows}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoints", nargs="+", metavar="CKPT",
                    help="checkpoint or policy files (tests/data/*.pt, a run's checkpoint.pt)")
    ap.add_argument("--settings", nargs="+", default=DEFAULT_SETTINGS, help="the changed settings to replay")
    ap.add_argument("--copies", type=int, default=4, help="native robots per setting")
    ap.add_argument("--steps", type=int, default=1000, help="control steps (one episode)")
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--no-joints", dest="joints", action="store_false", help="leave out each policy's joint table")
    ap.add_argument("--out", default=None, help="JSON file to write")
    args = ap.parse_args(argv)
    for path in args.checkpoints:
        if not os.path.isfile(path):
            ap.error(f"{path}: no such checkpoint file")
    if args.copies < 1 or args.steps < 1:
        ap.error(f"--copies {args.copies} and --steps {args.steps} must be positive")
    try:
        settings = [{"label": "own"}] + [parse_setting(t) for t in args.settings]
    except ValueError as e:
        ap.error(str(e))
    policies = [sensitivity(path, settings, args) for path in args.checkpoints]
    if args.out:
        from warpgym.cli import write_json  # noqa: PLC0415

        write_json(args.out, {"argv": sys.argv[1:] if argv is None else argv, "policies": policies})
    return 0


if __name__ == "__main__":
    sys.exit(main())
