"""A legged task's names resolved in MuJoCo's compile of its scene: the indices, defaults and per-joint numbers
the kernels read (``RobotIndex``), each name checked, with the scene's own names in the error when one is not
there."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from warpgym.tasks.legged.base import LeggedTask


@dataclass
class RobotIndex:
    root_body: int
    upright_body: int
    angvel_body: int
    com_body: int
    root_qpos: int
    root_dof: int
    joint_names: list[str]  # the actuated joints, in the model's order (mjlab's: the entity's)
    joint_qpos: np.ndarray
    joint_dof: np.ndarray
    default_root: np.ndarray  # (7,)
    default_joint_pos: np.ndarray
    soft_lo: np.ndarray
    soft_hi: np.ndarray
    joint_actuator: np.ndarray  # (J,) the actuator of each joint
    action_scale: np.ndarray  # (J,)
    foot_geoms: np.ndarray
    foot_site: np.ndarray
    foot_body: np.ndarray
    foot_found: np.ndarray
    foot_force: np.ndarray
    hit_force: np.ndarray  # (H,) sensordata addresses of the contact groups' forces
    hit_group: np.ndarray  # (H,) each one's group (kernels.legged.params: SELF_COLLISION ... ILLEGAL_CONTACT)
    imu_lin_vel: int
    imu_ang_vel: int
    angmom: int


def _names(mjm, kind) -> list[str]:
    import mujoco  # noqa: PLC0415

    obj = {"body": mujoco.mjtObj.mjOBJ_BODY, "site": mujoco.mjtObj.mjOBJ_SITE, "geom": mujoco.mjtObj.mjOBJ_GEOM,
           "sensor": mujoco.mjtObj.mjOBJ_SENSOR, "joint": mujoco.mjtObj.mjOBJ_JOINT}[kind]
    count = {"body": mjm.nbody, "site": mjm.nsite, "geom": mjm.ngeom, "sensor": mjm.nsensor, "joint": mjm.njnt}[kind]
    return [mujoco.mj_id2name(mjm, obj, i) or "" for i in range(count)]


def _find(task: LeggedTask, mjm, kind: str, field: str, name: str) -> int:
    names = _names(mjm, kind)
    if name not in names:
        known = [n for n in names if n]
        raise ValueError(f"{task.name}: {field}={getattr(task, field)!r}: the scene ({task.scene_path}) has no {kind} "
                         f"{name!r}; its {kind}s are {known}")
    return names.index(name)


def resolve(task: LeggedTask, mjm) -> RobotIndex:
    import mujoco  # noqa: PLC0415

    if abs(float(mjm.opt.timestep) - task.timestep) > 1e-12:
        raise ValueError(f"{task.name}: the scene's timestep is {mjm.opt.timestep}, the task's {task.timestep}")
    root = _find(task, mjm, "body", "root_body", task.root_body)
    free = [j for j in range(mjm.njnt) if int(mjm.jnt_type[j]) == int(mujoco.mjtJoint.mjJNT_FREE) and mjm.jnt_bodyid[j] == root]
    if not free:
        raise ValueError(f"{task.name}: root_body={task.root_body!r} has no free joint: name the robot's floating base")
    hinges = [j for j in range(mjm.njnt) if int(mjm.jnt_type[j]) in (int(mujoco.mjtJoint.mjJNT_HINGE), int(mujoco.mjtJoint.mjJNT_SLIDE))]
    joint_names = [_names(mjm, "joint")[j] for j in hinges]
    joint_qpos = np.array([mjm.jnt_qposadr[j] for j in hinges], np.int32)
    joint_dof = np.array([mjm.jnt_dofadr[j] for j in hinges], np.int32)
    keys = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_KEY, k) for k in range(mjm.nkey)]
    key_qpos = mjm.key_qpos[keys.index("init_state")] if "init_state" in keys else mjm.qpos0
    root_qpos, root_dof = int(mjm.jnt_qposadr[free[0]]), int(mjm.jnt_dofadr[free[0]])
    default_joint_pos = key_qpos[joint_qpos].astype(np.float32)
    rng = mjm.jnt_range[hinges].astype(np.float64)
    limited = mjm.jnt_limited[hinges].astype(bool)
    mean, half = rng.mean(axis=1), 0.5 * (rng[:, 1] - rng[:, 0]) * task.soft_joint_limit_factor
    soft_lo = np.where(limited, mean - half, -np.inf).astype(np.float32)
    soft_hi = np.where(limited, mean + half, np.inf).astype(np.float32)

    # the action has an entry per actuated joint in the model's joint order (mjlab's find_joints_by_actuator_names),
    # whatever order the actuators are declared in
    joint_actuator = np.full(len(hinges), -1, np.int32)
    for a in range(mjm.nu):
        if int(mjm.actuator_trntype[a]) != int(mujoco.mjtTrn.mjTRN_JOINT) or int(mjm.actuator_trnid[a, 0]) not in hinges:
            raise ValueError(f"{task.name}: actuator {a} does not drive one of the robot's joints")
        joint_actuator[hinges.index(int(mjm.actuator_trnid[a, 0]))] = a
    if (joint_actuator < 0).any() or mjm.nu != len(hinges):
        raise ValueError(f"{task.name}: every joint needs one position actuator ({mjm.nu} actuators, {len(hinges)} joints)")
    # mjlab's action scale: 0.25 * effort limit / stiffness of the joint's position actuator
    a = joint_actuator
    action_scale = (task.action_scale * mjm.actuator_forcerange[a, 1] / mjm.actuator_gainprm[a, 0]).astype(np.float32)

    def sensor(field, name):
        return int(mjm.sensor_adr[_find(task, mjm, "sensor", field, name)])

    from kernels.legged.params import ILLEGAL_CONTACT, SELF_COLLISION, SHANK_GROUND, TRUNK_GROUND  # noqa: PLC0415

    groups = [("self_collision_sensor", task.self_collision_sensor, SELF_COLLISION)] if task.self_collision_sensor else []
    groups += [("shank_sensors", n, SHANK_GROUND) for n in task.shank_sensors]
    groups += [("trunk_sensors", n, TRUNK_GROUND) for n in task.trunk_sensors]
    groups += [("illegal_contact_sensors", n, ILLEGAL_CONTACT) for n in task.illegal_contact_sensors]
    sites = np.array([_find(task, mjm, "site", "foot_sites", s) for s in task.foot_sites], np.int32)
    if len(task.foot_sensors) != len(sites):
        raise ValueError(f"{task.name}: foot_sensors names {len(task.foot_sensors)} feet, foot_sites {len(sites)}: "
                         "give one contact sensor per foot site")
    return RobotIndex(
        root_body=root, upright_body=_find(task, mjm, "body", "upright_body", task.upright_body),
        angvel_body=_find(task, mjm, "body", "angvel_body", task.angvel_body),
        com_body=_find(task, mjm, "body", "com_body", task.com_body), root_qpos=root_qpos, root_dof=root_dof,
        joint_names=joint_names, joint_qpos=joint_qpos, joint_dof=joint_dof,
        default_root=key_qpos[root_qpos:root_qpos + 7].astype(np.float32), default_joint_pos=default_joint_pos,
        soft_lo=soft_lo, soft_hi=soft_hi,
        joint_actuator=joint_actuator, action_scale=action_scale,
        foot_geoms=np.array([_find(task, mjm, "geom", "foot_geoms", g) for g in task.foot_geoms], np.int32),
        foot_site=sites, foot_body=mjm.site_bodyid[sites].astype(np.int32),
        foot_found=np.array([sensor("foot_sensors", s + "_found") for s in task.foot_sensors], np.int32),
        foot_force=np.array([sensor("foot_sensors", s + "_force") for s in task.foot_sensors], np.int32),
        imu_lin_vel=sensor("imu_lin_vel_sensor", task.imu_lin_vel_sensor),
        imu_ang_vel=sensor("imu_ang_vel_sensor", task.imu_ang_vel_sensor),
        angmom=sensor("angmom_sensor", task.angmom_sensor),
        hit_force=np.array([sensor(field, name + "_force") for field, name, _ in groups], np.int32),
        hit_group=np.array([g for _, _, g in groups], np.int32),
    )


def dims(task: LeggedTask, idx: RobotIndex, num_actions: int):
    """What the observation terms' sizes read: joints, actions, feet, height scan rays."""
    from warpgym.tasks.terms import Dims  # noqa: PLC0415

    scan = 0 if task.height_scan is None else len(task.height_scan.offsets)
    return Dims(joints=len(idx.joint_names), actions=num_actions, feet=len(idx.foot_site), scan=scan)


def policy_terms(task: LeggedTask, idx: RobotIndex, num_actions: int) -> list[tuple[str, int, str]]:
    """The policy's observation term by term, in order: (name, size, what it holds), from the task's table. The env
    sizes its observation by it and ``warpgym export`` writes it into the deployment contract."""
    from warpgym.tasks.terms import layout  # noqa: PLC0415

    return [(name, size, what) for name, _, size, what in
            layout(task.policy_obs, dims(task, idx, num_actions), f"{task.name}: policy_obs")]


def compile_task_scene(task: LeggedTask):
    """MuJoCo's compile of the task's scene with its generated ground (rough tasks; none on the flat floor):
    ``(CompiledModel, Terrain or None)``, the same model for the env, its drawings and native MuJoCo."""
    from warpgym.sim.scene import compile_scene  # noqa: PLC0415
    from warpgym.tasks.legged.terrain import add_to_spec  # noqa: PLC0415

    ground = None if task.terrain is None else task.terrain.generate(task.terrain_seed)
    if task.robot is not None:
        from warpgym.sim.gym_model import CompiledModel  # noqa: PLC0415
        from warpgym.tasks.legged.robot_file import compile_robot_scene  # noqa: PLC0415

        spec = task_scene(task)
        if ground is not None:
            add_to_spec(spec, ground)
        return CompiledModel(compile_robot_scene(spec, task.robot), task.robot.file), ground
    if ground is None:
        return compile_scene(task.scene_path), None
    return compile_scene(task.scene_path, lambda spec: add_to_spec(spec, ground)), ground


def task_scene(task: LeggedTask):
    """The ``MjSpec`` of a task's scene built from its robot: the robot's options changed by the task's, a floor on
    flat ground (an empty terrain body on rough), the self-collision sensor where the task reads one, and each group
    of the robot's touches whose sensors the task names."""
    from warpgym.tasks.legged.robot_file import build_scene  # noqa: PLC0415

    read = {"illegal": task.illegal_contact_sensors, "shank": task.shank_sensors, "trunk": task.trunk_sensors}
    touches = tuple((t.sensor, t.geoms) for t in task.robot.touches if read.get(t.role))
    return build_scene(task.robot, physics=dict(task.physics), floor=task.terrain is None,
                       self_collision=bool(task.self_collision_sensor), touches=touches)


def kernel_structs(task: LeggedTask, idx: RobotIndex, device: str):
    """The kernels' view of the task and its robot: ``LeggedParams`` and ``LeggedRobot``."""
    import warp as wp  # noqa: PLC0415

    from kernels.legged.params import LeggedParams, LeggedRobot  # noqa: PLC0415

    def arr(values, dtype=float):
        return wp.array(np.asarray(values, np.int32 if dtype == wp.int32 else np.float32), dtype=dtype, device=device)

    p = LeggedParams()
    p.physics_dt = task.timestep
    p.dt = task.timestep * task.decimation
    p.episode_length = task.episode_length
    ranges = [(0, task.lin_vel_x, task.lin_vel_y, task.ang_vel_z)]
    for step, x, y, z in sorted(task.command_stages, key=lambda s: s[0]):
        last = ranges[-1]
        ranges.append((step, x or last[1], y or last[2], z or last[3]))
    p.stage_steps = arr([s[0] for s in ranges], wp.int32)
    p.stage_ranges = wp.array(np.array([[*s[1], *s[2], *s[3]] for s in ranges], np.float32), dtype=float, device=device)
    p.heading_lo, p.heading_hi = task.heading
    p.resample_lo, p.resample_hi = task.resampling_time
    p.rel_standing, p.rel_heading, p.rel_forward = task.rel_standing_envs, task.rel_heading_envs, task.rel_forward_envs
    p.heading_stiffness = task.heading_control_stiffness
    p.forward_min = 0.3  # mjlab's forward-only worlds walk at least this fast [m/s]
    p.max_command_steps = task.resampling_time[1] / p.dt
    p.collision_force = task.self_collision_force
    p.foot_scan = int(task.foot_scan is not None)

    r = LeggedRobot()
    r.root_body, r.upright_body, r.angvel_body, r.com_body = idx.root_body, idx.upright_body, idx.angvel_body, idx.com_body
    r.root_qpos, r.root_dof = idx.root_qpos, idx.root_dof
    r.joint_qpos, r.joint_dof = arr(idx.joint_qpos, wp.int32), arr(idx.joint_dof, wp.int32)
    r.default_root, r.default_joint_pos = arr(idx.default_root), arr(idx.default_joint_pos)
    r.soft_lo, r.soft_hi = arr(idx.soft_lo), arr(idx.soft_hi)
    r.joint_actuator = arr(idx.joint_actuator, wp.int32)
    r.action_scale = arr(idx.action_scale)
    r.foot_site, r.foot_body = arr(idx.foot_site, wp.int32), arr(idx.foot_body, wp.int32)
    r.foot_geom = arr(idx.foot_geoms, wp.int32)
    r.foot_found, r.foot_force = arr(idx.foot_found, wp.int32), arr(idx.foot_force, wp.int32)
    r.imu_lin_vel, r.imu_ang_vel, r.angmom = idx.imu_lin_vel, idx.imu_ang_vel, idx.angmom
    r.hit_force, r.hit_group = arr(idx.hit_force, wp.int32), arr(idx.hit_group, wp.int32)
    return p, r
