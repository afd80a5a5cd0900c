"""The velocity tasks with any robot: a robot's definition (``robot_file.RobotFile``, in Python or a TOML file) gives
a legged task everything it names of a robot, and ``with_robot`` derives it.

- the parts the terms read, by their names in the built scene: the base, the torso (tilt, roll and pitch rates,
  centre of mass), the feet's geoms (friction), sites (heights, velocities) and contact sensors, the self-collision
  sensor, and on rough ground the groups of touches (an illegal one ends the episode; shanks and trunk are charged);
- the pose reward's stds per joint (the definition's ``posture``, or ``POSTURE``), the feet's friction randomised on
  one axis, or on three where the feet have condim 6 (mjlab's Go1);
- MuJoCo Warp's room for contacts and constraint rows, from what collides;
- last, the definition's own ``task`` changes (weights, ranges: what ``LeggedTask.replace`` takes).

``VelocityFlat-v0`` and ``VelocityRough-v0`` are mjlab's velocity task (``make_velocity_env_cfg``) and its rough
variant with nothing of a robot's own but what ``with_robot`` derives; their robot is the Go1 until one is given
(``gym.make_vec("warpgym/VelocityFlat-v0", robot="a1")``, ``warpgym train --robot my_robot.toml``).
"""

from __future__ import annotations

import os
from dataclasses import replace

import kernels.legged.events as ev
import kernels.legged.terminations as ends
from warpgym.tasks.legged.base import CRITIC_OBS, EVENTS, POLICY_OBS, TERMINATIONS, LeggedTask, with_height_scan
from warpgym.tasks.legged.robot_file import PREFIX, TOUCH_ROLES, RobotFile, foot_sites, robot_spec
from warpgym.tasks.terms import Event, PerJoint, Termination, Terms

# the pose reward's stds [rad] for a robot whose definition gives none: loose enough for any gait, tight standing
POSTURE = {"standing": 0.1, "walking": 0.3, "running": 0.5}
# MuJoCo Warp's contacts a geom of each type can make with the ground (a box or a mesh: its corners, up to 4)
CONTACTS_PER_GEOM = {"sphere": 1, "ellipsoid": 1, "capsule": 2, "cylinder": 4, "box": 4, "mesh": 4}

HERE = os.path.dirname(os.path.abspath(__file__))
ZOO_DIR = os.path.join(HERE, "zoo")


# mjlab's two robots, defined in Python beside their tasks (their actuators' numbers are derived from their motors)
PYTHON_ZOO = {"go1": "warpgym.tasks.legged.go1:GO1", "g1": "warpgym.tasks.legged.g1:G1"}


def zoo() -> dict[str, str]:
    """The robots warpgym has definitions of, by name: mjlab's two in Python (``module:NAME``) and the TOML files of
    warpgym/tasks/legged/zoo."""
    files = {os.path.splitext(f)[0]: os.path.join(ZOO_DIR, f) for f in sorted(os.listdir(ZOO_DIR)) if f.endswith(".toml")}
    return {**PYTHON_ZOO, **files}


def load_robot(robot) -> RobotFile:
    """A robot's definition from a ``RobotFile``, a zoo name ("a1") or a TOML definition's path."""
    if isinstance(robot, RobotFile):
        return robot
    if not isinstance(robot, str) or not robot:
        raise ValueError(f"robot={robot!r}: give a robot's definition (a RobotFile), a zoo name ({', '.join(zoo())}) "
                         "or a TOML definition's path")
    from warpgym.tasks.legged.definition import load_definition  # noqa: PLC0415

    known = zoo()
    if robot.lower() in PYTHON_ZOO:
        import importlib  # noqa: PLC0415

        module, _, name = PYTHON_ZOO[robot.lower()].partition(":")
        return getattr(importlib.import_module(module), name)
    if robot.lower() in known:
        return load_definition(known[robot.lower()])
    if robot.lower().endswith(".toml"):
        return load_definition(robot)
    if robot.lower().endswith((".urdf", ".xml")):
        raise ValueError(f"robot={robot!r} is a robot file; the task needs its definition too (the base, the feet, "
                         "the standing pose, the actuators): write a TOML definition that names it (docs/robots.md)")
    raise ValueError(f"robot={robot!r}: no zoo robot of that name ({', '.join(known)}) and not a .toml definition")


def robot_parts(robot: RobotFile, spec=None) -> dict:
    """The LeggedTask fields that name the robot's parts in the scene built from ``robot`` (its own spec: ``spec``)."""
    spec = spec or robot_spec(robot)
    torso = PREFIX + (robot.torso or robot.root)
    if robot.feet_are == "geom":
        foot_geoms = tuple(PREFIX + f for f in robot.feet)
    else:
        foot_geoms = tuple(PREFIX + g.name for f in robot.feet for g in _subtree_geoms(spec.body(f)) if _collides(g))
    names = [g.name for g in spec.geoms]
    by_role: dict[str, list[str]] = {role: [] for role in TOUCH_ROLES}
    for touch in robot.touches:
        if touch.role not in by_role:
            raise ValueError(f"touch {touch.sensor!r}: role={touch.role!r} is one of {list(by_role)}")
        hits = [n for n in names if any(_fullmatch(p, n) for p in touch.geoms)]
        if not hits:
            raise ValueError(f"touch {touch.sensor!r}: no geom of {robot.file} matches {list(touch.geoms)}; its "
                             f"geoms are {[n for n in names if n]}")
        by_role[touch.role] += [f"{touch.sensor}_{n}" for n in hits]
    return dict(root_body=PREFIX + robot.root, upright_body=torso, angvel_body=torso, com_body=torso,
                foot_geoms=foot_geoms, foot_sites=tuple(PREFIX + s for s in foot_sites(robot)),
                foot_sensors=tuple(f"feet_ground_contact_{f}" for f in robot.feet),
                self_collision_sensor=f"self_collision_{robot.root}" if robot.self_collisions else "",
                illegal_contact_sensors=tuple(by_role["illegal"]), shank_sensors=tuple(by_role["shank"]),
                trunk_sensors=tuple(by_role["trunk"]))


def _fullmatch(pattern: str, name: str) -> bool:
    import re  # noqa: PLC0415

    return re.fullmatch(pattern, name) is not None


def _collides(geom) -> bool:
    return bool(geom.contype or geom.conaffinity)


def _subtree_geoms(body):
    yield from body.geoms
    for child in body.bodies:
        yield from _subtree_geoms(child)


def contact_room(robot: RobotFile, spec, rough: bool) -> tuple[int, int]:
    """(nconmax, njmax) per world: the contacts the robot's colliding geoms can make with the ground (twice as many
    on rough ground, whose boxes and height fields give more), and a constraint row per friction direction of each
    (the cone's), beside a row per joint limit."""
    import mujoco  # noqa: PLC0415

    colliding = [g for g in spec.geoms if _collides(g)]
    kinds = {int(getattr(mujoco.mjtGeom, f"mjGEOM_{k.upper()}")): n for k, n in CONTACTS_PER_GEOM.items()}
    contacts = sum(kinds.get(int(g.type), 4) for g in colliding) * (2 if rough else 1)
    nconmax = max(32, contacts + 8)
    condim = max((int(g.condim) for g in colliding), default=3)
    cone = dict(robot.physics).get("cone", "pyramidal")
    rows = 2 * (condim - 1) if cone == "pyramidal" else condim
    return nconmax, max(300, nconmax * rows + 2 * len(spec.joints))


def posture_rewards(task: LeggedTask, robot: RobotFile) -> Terms:
    """The task's rewards with the pose term's stds the robot's (its definition's, else ``POSTURE``)."""
    if "pose" not in task.rewards:
        return task.rewards
    stds = {}
    for phase in ("standing", "walking", "running"):
        value = dict(robot.posture).get(phase, POSTURE[phase])
        stds[f"std_{phase}"] = PerJoint(value if isinstance(value, (dict, tuple)) else ((".*", float(value)),))
    unknown = sorted(set(dict(robot.posture)) - set(POSTURE))
    if unknown:
        raise ValueError(f"{robot.label}: posture has {unknown}; its phases are {list(POSTURE)}")
    return task.rewards.changed({"pose": {"params": stds}}, f"{task.name}: rewards")


def friction_events(task: LeggedTask, spec, foot_geoms: tuple[str, ...]) -> Terms:
    """The feet's friction randomised as mjlab randomises it: one axis (sliding) for condim-3 feet, each of the three
    for condim-6 feet (its Go1: sliding, torsional and rolling), in the place of the task's own."""
    names = {PREFIX + g.name: g for g in spec.geoms}
    six = any(int(names[g].condim) == 6 for g in foot_geoms if g in names)
    items = [(n, e) for n, e in task.events.items() if e.func is not ev.randomize_foot_friction]
    if six:
        axes = (("foot_friction_slide", 0, 0.3, 1.5, 0), ("foot_friction_spin", 1, 1e-4, 2e-2, 1),
                ("foot_friction_roll", 2, 1e-5, 5e-3, 1))
    else:
        axes = (("foot_friction", 0, 0.3, 1.2, 0),)
    where = next((i for i, (n, e) in enumerate(task.events.items()) if e.func is ev.randomize_foot_friction),
                 len(items))
    friction = [(n, Event(ev.randomize_foot_friction, "startup", {"axis": a, "value": (lo, hi), "log_uniform": log}))
                for n, a, lo, hi, log in axes]
    return Terms("event", items[:where] + friction + items[where:])


def with_robot(task: LeggedTask, robot) -> LeggedTask:
    """``task`` with ``robot`` (a RobotFile, a zoo name or a TOML path): every field that names the robot derived
    from its definition, then the definition's own ``task`` changes."""
    robot = load_robot(robot)
    spec = robot_spec(robot)
    parts = robot_parts(robot, spec)
    rough = task.terrain is not None
    if not rough:  # flat ground: no touches of the ground but the feet's
        parts.update(illegal_contact_sensors=(), shank_sensors=(), trunk_sensors=())
    nconmax, njmax = contact_room(robot, spec, rough)
    terminations = task.terminations
    if parts["illegal_contact_sensors"] and "illegal_contact" not in terminations:
        terminations = terminations.changed({"illegal_contact": Termination(ends.illegal_contact)},
                                            f"{task.name}: terminations")
    elif not parts["illegal_contact_sensors"] and "illegal_contact" in terminations:
        terminations = terminations.changed({"illegal_contact": None, **(
            {} if "fell_over" in terminations else {"fell_over": TERMINATIONS["fell_over"]})},
            f"{task.name}: terminations")
    out = replace(task, robot=robot, scene_file="", **parts, nconmax=nconmax, njmax=njmax,
                  rewards=posture_rewards(task, robot), events=friction_events(task, spec, parts["foot_geoms"]),
                  terminations=terminations)
    return out.replace(**dict(robot.task)) if robot.task else out


def velocity_task(robot, rough: bool = False) -> LeggedTask:
    """mjlab's velocity task for ``robot``, on flat ground or on its rough ground with the curriculum, the height
    scan under the base in both observations and the feet's scanned heights."""
    from warpgym.tasks.legged.go1 import ROUGH_CURRICULUM  # noqa: PLC0415
    from warpgym.tasks.legged.scan import GO1_FOOT_SCAN, TERRAIN_SCAN  # noqa: PLC0415

    base = LeggedTask(name="VelocityRough-v0" if rough else "VelocityFlat-v0",
                      mirrors="Mjlab-Velocity-Rough" if rough else "Mjlab-Velocity-Flat", scene_file="",
                      root_body="", upright_body="", angvel_body="", com_body="", foot_geoms=(), foot_sites=(),
                      foot_sensors=(), policy_obs=POLICY_OBS, critic_obs=CRITIC_OBS, events=EVENTS)
    if rough:
        base = replace(base, terrain=ROUGH_CURRICULUM, height_scan=TERRAIN_SCAN, foot_scan=GO1_FOOT_SCAN,
                       physics=(("ccd_iterations", 500),),
                       terminations=TERMINATIONS.changed({"out_of_terrain_bounds": Termination(
                           ends.out_of_terrain_bounds, time_out=True)}, "VelocityRough-v0: terminations"),
                       policy_obs=with_height_scan(POLICY_OBS, TERRAIN_SCAN.max_distance, noise=0.1),
                       critic_obs=with_height_scan(CRITIC_OBS, TERRAIN_SCAN.max_distance, noise=0.0))
    out = with_robot(base, robot)
    out.validate()
    return out


def stands(task: LeggedTask, seconds: float = 0.5) -> None:
    """The robot held at its standing pose by its actuators for ``seconds`` in native MuJoCo on flat ground, its base
    kept from tipping (a jig: a humanoid balances by its policy, not by its gains); one line naming what to change
    where its legs give way (the base below 70 % of its height), before a run spends time on a robot that cannot
    carry its weight."""
    import mujoco  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415

    from warpgym.tasks.legged.model import compile_task_scene, resolve  # noqa: PLC0415

    flat = replace(task, terrain=None, height_scan=None, foot_scan=None) if task.terrain is not None else task
    m = compile_task_scene(flat)[0].mjm
    idx = resolve(flat, m)
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    r, v = idx.root_qpos, idx.root_dof
    height, quat = float(d.qpos[r + 2]), d.qpos[r + 3:r + 7].copy()
    for _ in range(int(round(seconds / m.opt.timestep))):
        mujoco.mj_step(m, d)
        d.qpos[r + 3:r + 7], d.qvel[v + 3:v + 6] = quat, 0.0
    z = float(d.qpos[r + 2])
    if not np.isfinite(d.qpos).all() or z < 0.7 * height:
        name = task.robot.label if task.robot is not None else task.name
        raise ValueError(f"{name} cannot stand at its pose with its gains: after {seconds:g} s upright its base is at "
                         f"{z:.3f} m (from {height:.3f}): raise the actuators' stiffness, or fix base_height and "
                         "joint_pos")
