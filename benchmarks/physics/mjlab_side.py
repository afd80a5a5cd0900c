"""The mjlab side of warpgym's legged tasks: everything that imports mjlab, run by mjlab's own interpreter.

mjlab 1.6 pins MuJoCo and MuJoCo Warp 3.11 where warpgym pins 3.17, so mjlab lives in a virtual environment of
its own (CI's mjlab stage; on the GPU machine, its staged wheels) and this file imports nothing of warpgym. Its
commands:

- ``export DIR``: mjlab's velocity scenes (robot, actuators, sensors, floor or an empty terrain body, keyframe and
  the physics options its config sets after compiling) written as MJCF: the files warpgym's legged tasks compile
  (warpgym/tasks/legged/assets). The visual meshes are left out: they collide with nothing, and the physics of
  the file is the same without them (tests/test_legged.py compares the compiled fields).
- ``reference OUT.npz``: transitions of mjlab's own env on the CPU, with everything warpgym needs to start
  from the same state (tests/test_legged_judge.py steps warpgym's env from it and compares).
- ``models OUT.npz``: mjlab's compiled rough scenes for one ground seed, field by field (tests/test_legged_rough.py
  compares warpgym's compile of the same scene and ground).
- ``speed``: mjlab's env stepped with random actions, env-steps per second (benchmarks/learning/mjlab_side_by_side.py).
- ``returns CKPT``: a warpgym checkpoint's deterministic policy in mjlab's own env as it trains (noise, pushes and
  randomisation on), the return of each world's first episode (benchmarks/physics/legged_returns.py). The policy
  runs through ``agents``, the learner package, which imports nothing of warpgym.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

# mjlab asks for an OpenGL context and for ffmpeg when it is imported; neither is used here
os.environ.setdefault("MUJOCO_GL", "disable")

TASKS = {  # warpgym's id -> the mjlab task it mirrors
    "Go1VelocityFlat-v0": "Mjlab-Velocity-Flat-Unitree-Go1",
    "G1VelocityFlat-v0": "Mjlab-Velocity-Flat-Unitree-G1",
    "Go1VelocityRough-v0": "Mjlab-Velocity-Rough-Unitree-Go1",
    "G1VelocityRough-v0": "Mjlab-Velocity-Rough-Unitree-G1",
}
SCENE_FILES = {name: name.replace("Velocity", "_velocity_").replace("-v0", "").lower() + ".xml" for name in TASKS}
# the rough tasks' scenes: the robot and its sensors over an empty "terrain" body, which warpgym fills with its
# generated ground when it builds an env (warpgym.tasks.legged.terrain: the same ground for the same seed)
ROUGH_SCENES = {TASKS[name] for name in TASKS if "Rough" in name}
TERRAIN_PREFIXES = ("hf_texture_", "hf_material_", "hfield_")
TERRAIN_SEED = 0  # warpgym's rough tasks' default terrain_seed


def _env_cfg(task_id: str, num_envs: int):
    import mjlab.tasks  # noqa: F401  (registers the tasks)
    from mjlab.tasks.registry import load_env_cfg

    cfg = load_env_cfg(task_id)
    cfg.scene.num_envs = num_envs
    return cfg


# ---------------------------------------------------------------------------------------------------- export
def scene_xml(task_id: str) -> str:
    """mjlab's scene of ``task_id`` as MJCF, with the options mjlab applies after compiling and without the
    visual meshes."""
    import mujoco
    from mjlab.scene import Scene

    cfg = _env_cfg(task_id, 1)
    spec = Scene(cfg.scene, device="cpu").spec
    m = cfg.sim.mujoco
    opt = spec.option
    opt.timestep, opt.impratio, opt.iterations, opt.tolerance = m.timestep, m.impratio, m.iterations, m.tolerance
    opt.ls_iterations, opt.ls_tolerance, opt.ccd_iterations = m.ls_iterations, m.ls_tolerance, m.ccd_iterations
    opt.gravity = list(m.gravity)
    opt.cone = {"elliptic": mujoco.mjtCone.mjCONE_ELLIPTIC, "pyramidal": mujoco.mjtCone.mjCONE_PYRAMIDAL}[m.cone]
    opt.integrator = {"euler": mujoco.mjtIntegrator.mjINT_EULER,
                      "implicitfast": mujoco.mjtIntegrator.mjINT_IMPLICITFAST}[m.integrator]
    opt.jacobian = {"auto": mujoco.mjtJacobian.mjJAC_AUTO, "dense": mujoco.mjtJacobian.mjJAC_DENSE,
                    "sparse": mujoco.mjtJacobian.mjJAC_SPARSE}[m.jacobian]
    opt.solver = {"newton": mujoco.mjtSolver.mjSOL_NEWTON, "cg": mujoco.mjtSolver.mjSOL_CG}[m.solver]
    if task_id in ROUGH_SCENES:  # the generated ground and what only draws it (its lights, textures, materials)
        terrain = spec.body("terrain")
        for geom in list(terrain.geoms):
            spec.delete(geom)
        for light in [light for light in spec.lights if light.parent.name == "terrain"]:
            spec.delete(light)
        for item in [*spec.hfields, *spec.materials, *spec.textures]:
            if item.name.startswith(TERRAIN_PREFIXES):
                spec.delete(item)
    for geom in [g for g in spec.geoms if g.type == mujoco.mjtGeom.mjGEOM_MESH]:
        if geom.contype or geom.conaffinity:
            raise ValueError(f"{task_id}: mesh geom {geom.name!r} collides; it cannot be left out")
        spec.delete(geom)
    for mesh in list(spec.meshes):
        spec.delete(mesh)
    # MuJoCo 3.11 writes the main default class as an empty <default/>, which MuJoCo 3.17 refuses
    # ("empty class name"); it holds nothing
    xml = spec.to_xml().replace("<default>\n    <default/>\n", "<default>\n", 1)
    ground = ("and an empty terrain body, filled with the generated ground when an env is built"
              if task_id in ROUGH_SCENES else "and floor")
    header = (f"<!-- mjlab {_version()}'s scene of {task_id}: the robot of mjlab's asset zoo (from MuJoCo Menagerie, "
              f"BSD-3-Clause, see LICENSE-menagerie.txt), its actuators, sensors {ground} (mjlab, Apache-2.0, see "
              "NOTICE-mjlab.txt), with the physics options mjlab sets after compiling and without the visual "
              "meshes. Written by `python -m benchmarks.physics.mjlab_side export DIR` in mjlab's environment. -->\n")
    return header + xml


def _version() -> str:
    from importlib.metadata import version

    return version("mjlab")


def export(folder: str) -> None:
    os.makedirs(folder, exist_ok=True)
    for ours, theirs in TASKS.items():
        name = SCENE_FILES[ours]
        path = os.path.join(folder, name)
        with open(path, "w") as f:
            f.write(scene_xml(theirs))
        print(f"{theirs} -> {path}")


# ---------------------------------------------------------------------------------------------------- reference
def _np(t):
    return t.detach().cpu().numpy().copy()


def _parts(env):
    """The pieces of mjlab's env a transition reads and writes."""
    cmd = env.command_manager.get_term("twist")
    feet = env.scene["feet_ground_contact"]
    swing = env.reward_manager.get_term_cfg("foot_swing_height").func
    collision = env.scene.sensors.get("self_collision") if hasattr(env.scene, "sensors") else None
    return cmd, feet, swing, collision


def snapshot(env, foot_geoms) -> dict:
    """Everything of mjlab's env that warpgym's needs to start from the same state."""
    import mujoco

    cmd, feet, swing, _ = _parts(env)
    data, model = env.sim.data, env.sim.model
    mjm = env.sim.mj_model
    geom_ids = [mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_GEOM, g) for g in foot_geoms]
    kind = (cmd.is_heading_env.int() * 1 + cmd.is_standing_env.int() * 2 + cmd.is_forward_env.int() * 4)
    return {
        "qpos": _np(data.qpos), "qvel": _np(data.qvel), "warm_start": _np(data.qacc_warmstart),
        "action": _np(env.action_manager.action), "prev_action": _np(env.action_manager.prev_action),
        "command": _np(cmd.vel_command_b), "heading_target": _np(cmd.heading_target), "command_kind": _np(kind),
        "command_time_left": _np(cmd.time_left), "push_time_left": _np(env.event_manager._interval_term_time_left[0]),
        "air_time": _np(feet.data.current_air_time), "contact_time": _np(feet.data.current_contact_time),
        "peak_height": _np(swing.peak_heights), "foot_height": _np(env.scene["foot_height_scan"].data.heights),
        "encoder_bias": _np(env.scene["robot"].data.encoder_bias), "length": _np(env.episode_length_buf),
        "step_count": env.common_step_counter,
        "errors": _np(torch_stack([cmd.metrics["error_vel_xy"], cmd.metrics["error_vel_yaw"]])),
        "foot_friction": _np(model.geom_friction[:, geom_ids]), "body_ipos": _np(model.body_ipos),
        "dof_invweight0": _np(model.dof_invweight0), "body_invweight0": _np(model.body_invweight0),
    } | rough_state(env)


def rough_state(env) -> dict:
    """On rough ground, what else a world carries: its terrain level and kind, its start, and the ground's normal
    under its base that the upright term reads (from the last scan)."""
    terrain = env.scene.terrain
    if terrain is None or getattr(terrain, "terrain_origins", None) is None:
        return {}
    out = {"terrain_level": _np(terrain.terrain_levels), "terrain_kind": _np(terrain.terrain_types),
           "env_origin": _np(env.scene.env_origins)}
    upright = env.reward_manager.get_term_cfg("upright")
    if upright.params.get("terrain_sensor_names"):
        from mjlab.tasks.velocity.mdp.terrain_utils import terrain_normal_from_sensors

        out["terrain_normal"] = _np(terrain_normal_from_sensors(env, upright.params["terrain_sensor_names"]))
    return out


def torch_stack(tensors):
    import torch

    return torch.stack(tensors, dim=1)


MODEL_FIELDS = (
    "opt.timestep", "opt.integrator", "opt.cone", "opt.impratio", "opt.gravity", "opt.tolerance", "opt.ls_tolerance",
    "opt.iterations", "opt.ls_iterations", "opt.ccd_iterations", "opt.disableflags", "opt.enableflags",
    "body_mass", "body_inertia", "body_ipos", "body_iquat", "body_pos", "body_quat", "body_parentid",
    "jnt_type", "jnt_range", "jnt_limited", "jnt_stiffness", "jnt_solref", "jnt_solimp", "qpos0",
    "dof_damping", "dof_armature", "dof_frictionloss", "actuator_gainprm", "actuator_biasprm", "actuator_gaintype",
    "actuator_biastype", "actuator_forcerange", "actuator_forcelimited", "actuator_ctrllimited", "actuator_trnid",
    "sensor_type", "sensor_adr", "sensor_dim", "sensor_objtype", "sensor_reftype", "key_qpos",
    "site_pos", "site_bodyid",
)
GEOM_FIELDS = ("geom_type", "geom_size", "geom_pos", "geom_quat", "geom_friction", "geom_solref", "geom_solimp",
               "geom_condim", "geom_contype", "geom_conaffinity", "geom_priority", "geom_margin", "geom_gap",
               "geom_bodyid")


def model_fields(mjm) -> dict:
    """mjlab's compiled model, field by field (the geoms' by name: mjlab's model also holds the visual meshes)."""
    import mujoco
    import numpy as np

    out = {}
    for name in MODEL_FIELDS:
        obj = mjm
        for part in name.split("."):
            obj = getattr(obj, part)
        out["model/" + name] = np.asarray(obj).copy()
    names = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_GEOM, i) or "" for i in range(mjm.ngeom)]
    keep = [i for i, n in enumerate(names) if n]
    out["geom_names"] = np.array([names[i] for i in keep])
    # the sensors' objects by name: the geom ids differ where the visual meshes are left out
    out["sensor_objects"] = np.array([[mujoco.mj_id2name(mjm, int(mjm.sensor_objtype[i]), int(mjm.sensor_objid[i])) or "",
                                       mujoco.mj_id2name(mjm, int(mjm.sensor_reftype[i]), int(mjm.sensor_refid[i])) or ""]
                                      for i in range(mjm.nsensor)])
    for name in GEOM_FIELDS:
        out["geom/" + name] = np.asarray(getattr(mjm, name))[keep].copy()
    return out


def rough_models(out: str, seed: int) -> None:
    """mjlab's compiled scenes of its rough tasks with the ground generated from ``seed``, field by field as
    ``model_fields`` records them (keys prefixed by warpgym's task id), into OUT (.npz): the judge of warpgym's
    compile of the same scene and ground (tests/test_legged_rough.py)."""
    import numpy as np
    from mjlab.envs import ManagerBasedRlEnv

    arrays = {}
    for ours, theirs in TASKS.items():
        if theirs not in ROUGH_SCENES:
            continue
        cfg = _env_cfg(theirs, 1)
        cfg.scene.terrain.terrain_generator.seed = seed
        env = ManagerBasedRlEnv(cfg, device="cpu")  # its model as the env sets its options
        mjm = env.sim.mj_model
        arrays.update({f"{ours}/{k}": v for k, v in model_fields(mjm).items()})
        print(f"{theirs}: {mjm.ngeom} geoms, {mjm.nbody} bodies, {mjm.nsensor} sensors", flush=True)
        env.close()
    np.savez_compressed(out, seed=np.array(seed), mjlab=np.array(_version()), **arrays)


def edges(env) -> None:
    """A last transition with the rare cases in it: world 0 tipped 80 degrees about its x axis (it falls; where
    only a thigh's touch ends an episode, it is also lowered 0.12 m onto the ground), world 1 one step short of the
    time limit, world 2 with a knee past its soft limit."""
    import math

    data, robot = env.sim.data, env.scene["robot"]
    q = data.qpos[0, 3:7].clone()
    c, s = math.cos(math.radians(40.0)), math.sin(math.radians(40.0))
    data.qpos[0, 3:7] = torch_tensor([q[0] * c - q[1] * s, q[0] * s + q[1] * c, q[2] * c + q[3] * s, q[3] * c - q[2] * s])
    if "illegal_contact" in env.termination_manager.active_terms:  # tilt ends nothing here: a thigh on the ground does
        data.qpos[0, 2] -= 0.12
    env.episode_length_buf[1] = env.max_episode_length - 1
    limits = robot.data.soft_joint_pos_limits[2]
    data.qpos[2, 7 + 2] = limits[2, 1] + 0.09
    data.qvel[2, 6 + 2] = 5.0  # moving on outward: still past the soft limit after the step


def torch_tensor(values):
    import torch

    return torch.stack([torch.as_tensor(v) for v in values])


def reference(path: str, task: str, num_envs: int, warmup: int, steps: int, seed: int, action_std: float = 0.4,
              dist_envs: int = 256, resamples: int = 16) -> None:
    """``steps`` transitions of mjlab's env on the CPU (observation noise off), each from a state reached by
    ``warmup`` steps of random actions after the one before: the state before, the action, and what came out.
    The compared steps draw nothing: their command and push timers are moved past the step first."""
    import numpy as np
    import torch

    from mjlab.envs import ManagerBasedRlEnv

    theirs = TASKS[task]
    cfg = _env_cfg(theirs, num_envs)
    cfg.seed = seed
    cfg.observations["actor"].enable_corruption = False
    if theirs in ROUGH_SCENES:  # warpgym's default ground
        cfg.scene.terrain.terrain_generator.seed = TERRAIN_SEED
    friction = cfg.events.get("foot_friction_slide") or cfg.events["foot_friction"]
    foot_geoms = ["robot/" + g for g in friction.params["asset_cfg"].geom_names]
    env = ManagerBasedRlEnv(cfg, device="cpu")
    gen = torch.Generator().manual_seed(seed)
    cmd, _, _, _ = _parts(env)
    nu = env.action_manager.total_action_dim
    names = list(env.reward_manager._term_names)
    record: dict[str, list] = {}

    def add(prefix, values):
        for key, value in values.items():
            record.setdefault(prefix + key, []).append(value)

    env.reset()
    for k in range(steps):
        for _ in range(warmup):
            env.step(action_std * torch.randn(num_envs, nu, generator=gen))
        if k == steps - 1:
            edges(env)
        cmd.time_left[:] = 100.0
        env.event_manager._interval_term_time_left[0][:] = 100.0
        add("before/", snapshot(env, foot_geoms))
        action = action_std * torch.randn(num_envs, nu, generator=gen)
        obs, reward, terminated, time_outs, _ = env.step(action)
        # mjlab's contact sensor caches what its rewards read after the last physics step, and only a reset (of
        # any world) clears that cache before the observation: the critic's contacts and forces come from the last
        # physics step in a step without resets, from the forward pass in one with them. The observation again
        # with the cache cleared is the second case, which warpgym always computes.
        feet = env.scene["feet_ground_contact"]
        feet._invalidate_cache()
        fresh = env.observation_manager.compute_group("critic")
        add("", {"action": _np(action), "actor": _np(obs["actor"]), "critic": _np(obs["critic"]),
                 "critic_fresh": _np(fresh),
                 "reward": _np(reward), "terms": _np(env.reward_manager._step_reward) * env.step_dt,
                 "terminated": _np(terminated), "time_outs": _np(time_outs)})
        add("after/", snapshot(env, foot_geoms))
    arrays = {k: np.stack(v) for k, v in record.items()}
    arrays.update(model_fields(env.sim.mj_model))
    arrays["term_names"] = np.array(names)
    arrays["foot_geoms"] = np.array(foot_geoms)
    env.close()
    if dist_envs > 0:
        arrays.update(distributions(theirs, dist_envs, resamples, seed, foot_geoms))
    np.savez_compressed(path, **arrays)
    print(f"{theirs}: {steps} transitions of {num_envs} worlds, draws of {dist_envs} -> {path}")


def distributions(task_id: str, num_envs: int, resamples: int, seed: int, foot_geoms: list[str]) -> dict:
    """What mjlab draws, for a statistical comparison: the startup randomisation of ``num_envs`` worlds, the push
    timers a reset draws, and ``resamples`` draws of every world's command (its _resample, before steering)."""
    import numpy as np

    from mjlab.envs import ManagerBasedRlEnv

    cfg = _env_cfg(task_id, num_envs)
    cfg.seed = seed + 1
    env = ManagerBasedRlEnv(cfg, device="cpu")
    env.reset()
    state = snapshot(env, foot_geoms)
    cmd, _, _, _ = _parts(env)
    ids = torch_arange(num_envs)
    draws: dict[str, list] = {}
    for _ in range(resamples):
        cmd._resample(ids)
        for key, value in (("command", cmd.vel_command_b), ("heading_target", cmd.heading_target),
                           ("heading", cmd.is_heading_env), ("standing", cmd.is_standing_env),
                           ("forward", cmd.is_forward_env), ("time_left", cmd.time_left)):
            draws.setdefault(key, []).append(_np(value).astype(np.float32))
    out = {"dist/" + k: np.concatenate(v) for k, v in draws.items()}
    out.update({"dist/foot_friction": state["foot_friction"], "dist/body_ipos": state["body_ipos"],
                "dist/encoder_bias": state["encoder_bias"], "dist/push_time_left": state["push_time_left"],
                "dist/qpos": state["qpos"]})
    env.close()
    return out


def torch_arange(n: int):
    import torch

    return torch.arange(n, dtype=torch.long)


# ---------------------------------------------------------------------------------------------------- speed
def speed(task: str, sizes: list[int], steps: int, warmup: int, repeats: int, out: str) -> None:
    """mjlab's env stepped with uniform random actions in [-1, 1] on cuda:0: env-steps per second of each size, each
    repeat ``steps`` steps after ``warmup``, timed between two device synchronisations."""
    import torch

    from mjlab.envs import ManagerBasedRlEnv

    rows = []
    for n in sizes:
        start = time.perf_counter()
        env = ManagerBasedRlEnv(_env_cfg(TASKS[task], n), device="cuda:0")
        env.reset()
        built = time.perf_counter() - start
        nu = env.action_manager.total_action_dim
        rates = []
        for _ in range(repeats):
            for _ in range(warmup):
                env.step(torch.rand(n, nu, device="cuda:0") * 2 - 1)
            torch.cuda.synchronize()
            t = time.perf_counter()
            for _ in range(steps):
                env.step(torch.rand(n, nu, device="cuda:0") * 2 - 1)
            torch.cuda.synchronize()
            rates.append(n * steps / (time.perf_counter() - t))
        env.close()
        del env
        torch.cuda.empty_cache()
        rows.append({"num_envs": n, "env_steps_per_s": rates, "build_s": built})
        print(f"mjlab {TASKS[task]} x {n}: {sorted(rates)[len(rates) // 2] / 1e3:.0f} k env-steps/s (build {built:.0f} s)",
              flush=True)
    with open(out, "w") as f:
        json.dump({"framework": "mjlab", "mjlab": _version(), "task": task, "mirrors": TASKS[task], "steps": steps,
                   "warmup": warmup, "rows": rows, "device": torch.cuda.get_device_name(0)}, f, indent=1)


# ---------------------------------------------------------------------------------------------------- returns
def returns(checkpoint: str, task: str, num_envs: int, seed: int, out: str) -> None:
    """Each world's first episode under the checkpoint's mean action in mjlab's env on the CPU: its return (the sum
    of the env's rewards, as rsl_rl counts them), its length and whether it fell, as JSON into ``out``."""
    import torch

    from agents.checkpoint import load, policy_from_checkpoint
    from benchmarks.physics.first_episodes import first_episodes
    from mjlab.envs import ManagerBasedRlEnv

    ckpt = load(checkpoint, torch.device("cpu"))
    spec = ckpt["spec"]
    cfg = _env_cfg(TASKS[task], num_envs)
    cfg.seed = seed
    env = ManagerBasedRlEnv(cfg, device="cpu")
    policy, normalize = policy_from_checkpoint(ckpt, spec["num_obs"], spec["num_actions"], torch.device("cpu"))
    obs, _ = env.reset()
    started = time.perf_counter()
    episodes = first_episodes(env.step, lambda o: policy.act_deterministic(normalize(o["actor"])), obs, num_envs,
                              int(env.max_episode_length))
    env.close()
    with open(out, "w") as f:
        json.dump({"framework": "mjlab", "mjlab": _version(), "task": task, "mirrors": TASKS[task], "seed": seed,
                   **episodes, "seconds": time.perf_counter() - started}, f)
    print(f"mjlab {TASKS[task]} x {num_envs}: mean return {sum(episodes['returns']) / num_envs:.2f}, "
          f"{sum(episodes['fell'])} fell", flush=True)


def terrain(out: str, seeds: list[int], points: int) -> None:
    """mjlab's rough ground (``ROUGH_TERRAINS_CFG``) for each seed, compiled by MuJoCo, as drawn at random (keys
    ``seedS_*``) and in curriculum mode, one kind a column, as its rough tasks build it (``curriculum_seedS_*``):
    each patch's start and the heights under ``points`` (x, y) drawn over the grid and its border, by MuJoCo's ray
    cast straight down, into OUT (.npz). warpgym's generator is judged on it (tests/test_terrain.py)."""
    from dataclasses import replace  # noqa: PLC0415

    import mujoco  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415
    from mjlab.terrains.config import ROUGH_TERRAINS_CFG  # noqa: PLC0415
    from mjlab.terrains.terrain_generator import TerrainGenerator  # noqa: PLC0415

    from benchmarks.physics.ground_rays import heights  # noqa: PLC0415  (numpy and MuJoCo only, as mjlab's env has)

    rng = np.random.default_rng(0)
    arrays = {}
    for seed in seeds:
        for prefix, curriculum in (("", False), ("curriculum_", True)):
            gen = TerrainGenerator(replace(ROUGH_TERRAINS_CFG, seed=seed, curriculum=curriculum))
            spec = mujoco.MjSpec()
            gen.compile(spec)
            mjm = spec.compile()
            rows, cols = gen.terrain_origins.shape[:2]
            half = np.array([rows * gen.cfg.size[0], cols * gen.cfg.size[1]]) / 2 + 1.0  # 1 m of the border too
            xy = rng.uniform(-half, half, size=(points, 2))
            z = heights(mjm, xy)  # the rays warpgym's compile is judged by
            arrays[f"{prefix}seed{seed}_points"] = xy
            arrays[f"{prefix}seed{seed}_heights"] = z
            arrays[f"{prefix}seed{seed}_origins"] = gen.terrain_origins
            print(f"seed {seed}{' (curriculum)' if curriculum else ''}: {mjm.ngeom} geoms, {mjm.nhfield} heightfields, "
                  f"heights {np.nanmin(z):.3f} to {np.nanmax(z):.3f} m", flush=True)
    np.savez_compressed(out, seeds=np.array(seeds), mjlab=np.array(_version()), **arrays)


# ---------------------------------------------------------------------------------------------------- main
def main(argv=None) -> None:
    p = argparse.ArgumentParser(prog="python -m benchmarks.physics.mjlab_side", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    e = sub.add_parser("export", help="write mjlab's velocity scenes as MJCF into DIR")
    e.add_argument("folder")
    r = sub.add_parser("reference", help="record transitions of mjlab's env on the CPU into OUT (.npz)")
    r.add_argument("out")
    r.add_argument("--task", choices=list(TASKS), required=True)
    r.add_argument("--envs", type=int, default=8)
    r.add_argument("--warmup", type=int, default=25)
    r.add_argument("--steps", type=int, default=4)
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--action-std", type=float, default=0.4)
    r.add_argument("--dist-envs", type=int, default=256, help="worlds of the distributions' draws (0: none)")
    r.add_argument("--resamples", type=int, default=16)
    sp = sub.add_parser("speed", help="mjlab's env with random actions on cuda:0, env-steps/s, as JSON into OUT")
    sp.add_argument("out")
    sp.add_argument("--task", choices=list(TASKS), required=True)
    sp.add_argument("--num-envs", type=int, nargs="+", default=[4096, 8192])
    sp.add_argument("--steps", type=int, default=200)
    sp.add_argument("--warmup", type=int, default=20)
    sp.add_argument("--repeats", type=int, default=3)
    rt = sub.add_parser("returns", help="a warpgym policy in mjlab's env on the CPU, first-episode returns as JSON")
    rt.add_argument("checkpoint")
    rt.add_argument("out")
    rt.add_argument("--task", choices=list(TASKS), required=True)
    rt.add_argument("--num-envs", type=int, default=64)
    rt.add_argument("--seed", type=int, default=0)
    tr = sub.add_parser("terrain", help="mjlab's rough ground for some seeds: starts and ray-cast heights (.npz)")
    tr.add_argument("out")
    tr.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    tr.add_argument("--points", type=int, default=4000)
    md = sub.add_parser("models", help="mjlab's compiled rough scenes for a ground seed, field by field (.npz)")
    md.add_argument("out")
    md.add_argument("--seed", type=int, default=0)
    args = p.parse_args(argv)
    if args.command == "models":
        rough_models(args.out, args.seed)
    elif args.command == "terrain":
        terrain(args.out, args.seeds, args.points)
    elif args.command == "returns":
        returns(args.checkpoint, args.task, args.num_envs, args.seed, args.out)
    elif args.command == "speed":
        speed(args.task, args.num_envs, args.steps, args.warmup, args.repeats, args.out)
    elif args.command == "export":
        export(args.folder)
    elif args.command == "reference":
        reference(args.out, args.task, args.envs, args.warmup, args.steps, args.seed, args.action_std, args.dist_envs,
                  args.resamples)


if __name__ == "__main__":
    main(sys.argv[1:])
