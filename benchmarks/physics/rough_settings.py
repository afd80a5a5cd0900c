"""Which MuJoCo Warp settings step the rough tasks fastest without changing what the robot meets.

On rough ground MuJoCo Warp's own step is most of the task's (117 k of 112 k env-steps/s for the Go1 at 4096 worlds
on an H200, against 457 k on flat ground), so the settings that decide how it finds and holds contacts are the
levers: the broadphase (MuJoCo Warp picks its all-pairs kind, NXN, for these scenes: 30 robot geoms against 554
ground geoms; SAP_TILE and SAP_SEGMENTED sort and sweep), the constraint rows per world (mjlab's 1500), the contacts
a contact sensor considers (mjlab's 500) and the CCD iterations (mjlab's 500); and, not a setting, the ground's
geometry: the stairs as heightfields (ground_variants.py's ``stairs_cell``: 74 ground geoms) or the whole grid as one
(``ground_cell``: 5). For each variant:

- env-steps/s of the bare step (uniform random actions in [-1, 1], as ``warpgym bench --legged``) and of MuJoCo
  Warp's step alone, the median of ``--repeats``;
- the peak constraint rows of a world and contacts of all worlds, and the overflow faults (a variant that drops
  constraints changes the physics);
- its agreement with the first variant (mjlab's settings): from the same seed, the same actions for ``--check-steps``
  control steps, the largest difference of any world's qpos and of its sensor data (the contact sensors the rewards
  and terminations read among them), the worlds whose qpos moved apart by more than ``QPOS_TOL`` and the worlds
  whose contact count differs. On a GPU the same settings do not repeat bit for bit (contacts are gathered with
  atomics, so their order, and the solver's rounding, change from run to run, and a world near a threshold can end
  its episode in one run and not the other), so the first variant is also run twice: its run-to-run difference is
  the floor the others are read against.

    python -m benchmarks.physics.rough_settings --tasks Go1VelocityRough-v0 G1VelocityRough-v0 --num-envs 4096 \\
        --out rough_settings.json
    python -m benchmarks.physics.rough_settings --report rough_settings.json     # its table again
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np
import torch

VARIANTS = {  # name: settings changed from the task's (mjlab's); "mjlab" first, the reference of the others
    "mjlab": {},
    "sap_tile": {"broadphase": "SAP_TILE"},
    "sap_segmented": {"broadphase": "SAP_SEGMENTED"},
    "njmax_300": {"njmax": 300},
    "maxmatch_64": {"contact_sensor_maxmatch": 64},
    "ccd_50": {"ccd_iterations": 50},
    "sap_tile_njmax_300_maxmatch_64": {"broadphase": "SAP_TILE", "njmax": 300, "contact_sensor_maxmatch": 64},
    # not a setting but the ground's geometry: each stairs patch one heightfield (74 ground geoms instead of 554);
    # it differs from mjlab's ground at the steps' edges by design, so its agreement columns are not a check
    "stairs_heightfield_5cm": {"stairs_cell": 0.05},
    # the whole grid as one heightfield (5 ground geoms): every patch resampled every 5 cm
    "ground_heightfield_5cm": {"ground_cell": 0.05},
}
TASK_FIELDS = ("njmax", "contact_sensor_maxmatch")  # LeggedTask fields
TERRAIN_FIELDS = ("stairs_cell", "ground_cell")  # ground_variants.Resampled fields; the rest are MuJoCo Warp options
QPOS_TOL = 1e-3  # [m or rad] a world whose qpos moved further apart than this counts as diverged


def build(task: str, num_envs: int, device: str, settings: dict):
    """The task's env with ``settings`` applied: task fields at construction, MuJoCo Warp options before the first
    step (they are read when a kernel is launched, and the step's graph is captured at the first step)."""
    import mujoco_warp  # noqa: PLC0415

    from benchmarks.physics.ground_variants import Resampled  # noqa: PLC0415
    from warpgym.envs.legged import LeggedVecEnv  # noqa: PLC0415
    from warpgym.tasks.legged import get_legged_task  # noqa: PLC0415

    fields = {k: v for k, v in settings.items() if k in TASK_FIELDS}
    ground = {k: v for k, v in settings.items() if k in TERRAIN_FIELDS}
    if ground:
        fields["terrain"] = Resampled.of(get_legged_task(task).terrain, **ground)
    env = LeggedVecEnv(task, num_envs=num_envs, device=device, seed=0, **fields)
    opt = env.sim.m.opt
    if "broadphase" in settings:
        opt.broadphase = mujoco_warp.BroadphaseType[settings["broadphase"]]
    if "ccd_iterations" in settings:
        opt.ccd_iterations = int(settings["ccd_iterations"])
    return env


def broadphase_name(value) -> str:
    import mujoco_warp  # noqa: PLC0415

    return mujoco_warp.BroadphaseType(int(value)).name


def trajectory(env, steps: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """qpos, contacts per world and sensor data (the contact sensors' among them) after ``steps`` control steps from
    ``reset(seed=0)`` under fixed actions."""
    gen = torch.Generator(device="cpu").manual_seed(0)
    env.reset(seed=0)
    for _ in range(steps):
        env.step((torch.rand(env.num_envs, env.num_actions, generator=gen) * 2 - 1).to(env.device))
    d = env.sim.d
    worlds = d.contact.worldid.numpy()[: int(d.nacon.numpy()[0])]
    return d.qpos.numpy().copy(), np.bincount(worlds, minlength=env.num_envs), d.sensordata.numpy().copy()


def agreement(got: tuple, reference: tuple) -> dict:
    """How far one trajectory's end (``trajectory``'s three arrays) is from another's."""
    per_world = np.abs(got[0] - reference[0]).max(axis=1)
    return {"qpos_max_abs_diff": float(per_world.max()), "worlds_qpos_apart": int((per_world > QPOS_TOL).sum()),
            "worlds_with_other_contact_counts": int((got[1] != reference[1]).sum()),
            "sensordata_max_abs_diff": float(np.abs(got[2] - reference[2]).max())}


def floor(task: str, num_envs: int, device: str, settings: dict, got: tuple, check_steps: int) -> dict:
    """The reference's settings in a second env of their own, against the first: the run-to-run floor. (Not the
    same env again: its reset keeps the curriculum's levels, which the first run's ended episodes moved, and a
    world on another level starts elsewhere.)"""
    again = build(task, num_envs, device, settings)
    try:
        return agreement(trajectory(again, check_steps), got)
    finally:
        again.close()


def measure(task: str, name: str, num_envs: int, device: str, steps: int, warmup: int, repeats: int,
            check_steps: int, reference: tuple | None) -> tuple[dict, tuple]:
    from warpgym.cli.bench import timed  # noqa: PLC0415
    from warpgym.cli.bench.suite import mujoco_warp_loop  # noqa: PLC0415

    settings = VARIANTS[name]
    start = time.perf_counter()
    env = build(task, num_envs, device, settings)
    built = time.perf_counter() - start
    got = trajectory(env, check_steps)
    agree = agreement(got, reference) if reference is not None else {
        "run_to_run": floor(task, num_envs, device, settings, got, check_steps)}

    def env_step():
        env.step(torch.rand(num_envs, env.num_actions, device=env.device) * 2 - 1)

    rates, physics, raw = [], [], None
    for _ in range(repeats):
        for _ in range(warmup):
            env_step()
        raw = raw or mujoco_warp_loop(env, forward=True)
        physics.append(num_envs * steps / timed(raw, steps, 1, device)[0])
        env.reset(seed=0)  # the raw loop's states may be anything: the env's timing starts from a reset
        for _ in range(warmup):
            env_step()
        rates.append(num_envs * steps / timed(env_step, steps, 1, device)[0])
    row = {"task": task, "variant": name, "settings": settings, "num_envs": num_envs, "build_s": built,
           "env_steps_per_s": rates, "mjwarp_steps_per_s": physics,
           "faults": {k: int(v) for k, v in env.fault_counters().items()}, "solver_load": env.sim.solver_load(),
           "broadphase": broadphase_name(env.sim.m.opt.broadphase)} | agree
    env.close()
    return row, got


def apart(row: dict, key: str) -> str:
    """A variant's count against the reference, or the reference's run-to-run floor (in brackets)."""
    return f"({row['run_to_run'][key]})" if "run_to_run" in row else str(row.get(key, "-"))


def table(rows: list[dict]) -> str:
    lines = ["| task | variant | env-steps/s | MuJoCo Warp alone | vs mjlab's settings | peak rows / world | overflows "
             f"| worlds apart (qpos > {QPOS_TOL:g}) | worlds, other contacts |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    base = {}
    for r in rows:
        env = statistics.median(r["env_steps_per_s"])
        base.setdefault(r["task"], env)
        lines.append(f"| {r['task']} | {r['variant']} | {env / 1e3:.0f} k | {statistics.median(r['mjwarp_steps_per_s']) / 1e3:.0f} k "
                     f"| {env / base[r['task']]:.2f}x | {r['solver_load']['peak_constraints_per_world']} "
                     f"| {r['faults'].get('solver_overflows', 0)} | {apart(r, 'worlds_qpos_apart')} "
                     f"| {apart(r, 'worlds_with_other_contact_counts')} |")
    return "\n".join(lines)


def report(path: str) -> str:
    """A written study's table under the line that says where and how it ran."""
    with open(path) as f:
        doc = json.load(f)
    rows = doc["rows"]
    r = rows[0]
    head = f"{doc['device']}, {doc['date']}: {r['num_envs']} worlds, env-steps/s the median of {len(r['env_steps_per_s'])} timings"
    if any("run_to_run" in row for row in rows):  # studies before the floor was run have none
        head += "; in brackets, mjlab's settings against a second run of themselves"
    return head + "\n\n" + table(rows)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tasks", nargs="+", default=["Go1VelocityRough-v0", "G1VelocityRough-v0"])
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS),
                    help="the first is the reference the others are compared with")
    ap.add_argument("--num-envs", type=int, default=4096)
    ap.add_argument("--device", default="cuda:0")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--warmup", type=int, default=20)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--check-steps", type=int, default=5, help="control steps of the agreement check")
    ap.add_argument("--out", help="JSON file to write")
    ap.add_argument("--report", metavar="JSON", help="print the table of a study written before (its --out)")
    args = ap.parse_args(argv)
    if args.report:
        print(report(args.report))
        return 0
    from warpgym.cli import write_json  # noqa: PLC0415

    rows = []
    for task in args.tasks:
        reference = None
        for name in args.variants:
            row, got = measure(task, name, args.num_envs, args.device, args.steps, args.warmup, args.repeats,
                               args.check_steps, reference)
            reference = reference if reference is not None else got
            rows.append(row)
            print(table([r for r in rows if r["task"] == task]).splitlines()[-1], flush=True)
            if args.out:  # after every variant: a call cut short keeps the rows so far
                write_json(args.out, {"device": torch.cuda.get_device_name(0) if args.device.startswith("cuda")
                                      else args.device, "date": time.strftime("%Y-%m-%d"), "rows": rows})
    print(table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
