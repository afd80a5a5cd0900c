"""A legged robot from its own MJCF or URDF file: the scene a velocity task steps, built with MuJoCo's MjSpec from
the file and a few numbers, the way mjlab's entity and scene configs build theirs.

A ``RobotFile`` names the file, the base body, the feet (collision geoms, or bodies' subtrees), the standing pose,
the actuators (PD position targets: stiffness and damping given, or derived from the reflected inertia, a natural
frequency and a damping ratio) and what collides. ``build_scene`` attaches the robot under the ``robot/`` prefix
beside a body named ``terrain`` (a floor, or empty for the generated ground), keeps its collision geometry (visual
meshes are dropped: the scene is for stepping), gives the base a free joint where the file has none (URDF has no
floating base), adds what the velocity task reads and the file lacks (an IMU site at the base with its gyro and
velocimeter, the base's subtree angular momentum, a site at each foot), applies the collision policy, adds a
position actuator per actuated joint and the contact sensors the task reads, and writes the standing pose as the
keyframe. MuJoCo's compile of the result is the model; tests/test_robot_file.py checks the Go1's and the G1's
against the scenes committed from mjlab's environment, field by field.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field

PREFIX = "robot/"
NETFORCE = 3  # a contact sensor's reduction to the net force of its matches (MuJoCo's mjtConDataReduce; no Python enum)
TOUCH_ROLES = ("illegal", "shank", "trunk")
CLEARANCE = 0.001  # [m] between the floor and the feet of a standing pose whose base height is derived  # what a group of touches of the ground is for (LeggedTask's sensors)


# MuJoCo's options of mjlab's velocity tasks (its SimulationCfg; the Go1's task changes the cone and impratio)
PHYSICS = {"timestep": 0.005, "integrator": "implicitfast", "cone": "pyramidal", "impratio": 1.0, "iterations": 10,
           "ls_iterations": 20, "ccd_iterations": 50}


def first_match(value, name: str, where: str, default=KeyError):
    """``value`` for the geom or joint ``name``: the value itself, or the value of the first pattern of a
    ``{pattern: value}`` mapping (or a tuple of pairs) that matches ``name`` in full; ``default`` where none does
    (without one, an error that says so)."""
    if not isinstance(value, (dict, tuple)) or (isinstance(value, tuple) and not all(
            isinstance(p, tuple) and len(p) == 2 and isinstance(p[0], str) for p in value)):
        return value
    pairs = value.items() if isinstance(value, dict) else value
    for pattern, v in pairs:
        if re.fullmatch(pattern, name) is not None:
            return v
    if default is not KeyError:
        return default
    raise ValueError(f"{where}: no pattern of {[p for p, _ in pairs]} matches {name!r}: add one (a catch-all '.*' "
                     "serves)")


def matches(patterns, name: str) -> bool:
    return any(re.fullmatch(p, name) is not None for p in patterns)


@dataclass(frozen=True)
class Actuator:
    """Position actuators on the joints whose names match ``joints`` (a regular expression matched in full), in the
    file's joint order. ``stiffness``/``damping`` [N m/rad, N m s/rad] given, or derived from ``armature`` (the
    reflected inertia, kg m^2) as mjlab derives them: stiffness = armature * w^2, damping = 2 * ratio * armature * w,
    w = 2 pi * ``natural_frequency`` [Hz]. ``armature`` is also the joints' armature (None: the file's);
    ``effort_limit`` [N m] bounds the force (None: each joint's own limit in the file, a URDF's ``effort``)."""

    joints: str | tuple[str, ...]  # one pattern or several
    effort_limit: float | None = None
    armature: float | None = None
    stiffness: float | None = None
    damping: float | None = None
    natural_frequency: float | None = None
    damping_ratio: float | None = None

    def gains(self) -> tuple[float, float]:
        if self.stiffness is not None and self.damping is not None:
            return float(self.stiffness), float(self.damping)
        if self.natural_frequency is None or self.damping_ratio is None or not (self.armature or 0) > 0:
            raise ValueError(f"actuator {self.joints!r}: give stiffness and damping, or an armature > 0 with a "
                             "natural_frequency [Hz] and a damping_ratio to derive them from")
        w = 2.0 * math.pi * self.natural_frequency
        return self.armature * w * w, 2.0 * self.damping_ratio * self.armature * w

    @property
    def patterns(self) -> tuple[str, ...]:
        return (self.joints,) if isinstance(self.joints, str) else tuple(self.joints)


@dataclass(frozen=True)
class Collision:
    """The collision policy (mjlab's ``CollisionCfg``): the geoms whose names match one of ``geoms`` take these
    values, each a value or ``{pattern: value}`` (the first pattern that matches a geom's name in full); every other
    geom collides with nothing. ``None`` keeps the file's value."""

    geoms: tuple[str, ...]
    contype: int | dict = 1
    conaffinity: int | dict = 1
    condim: int | dict = 3
    priority: int | dict = 0
    friction: tuple | dict | None = None
    solref: tuple | dict | None = None
    solimp: tuple | dict | None = None


@dataclass(frozen=True)
class Touch:
    """A group of the robot's collision geoms whose touches of the ground a rough task reads, each geom a contact
    sensor ``<name>_<geom>``: ``role`` "illegal" (a touch ends the episode), "shank" or "trunk" (a touch is
    charged); ``name`` defaults to ``<role>_ground_touch``."""

    role: str
    geoms: tuple[str, ...]
    name: str = ""

    @property
    def sensor(self) -> str:
        return self.name or f"{self.role}_ground_touch"


@dataclass(frozen=True)
class RobotFile:
    """A legged robot's MJCF or URDF file and what the velocity tasks need to know of it."""

    file: str
    root: str  # the floating base's body
    feet: tuple[str, ...]  # the feet, in the task's foot order: collision geoms, or bodies (``feet_are="subtree"``)
    base_height: float | None = None  # the standing pose's base height [m]; None: the feet's lowest point on the floor
    joint_pos: dict = field(default_factory=dict)  # {joint pattern: angle [rad]}; joints no pattern names stand at 0
    actuators: tuple[Actuator, ...] = ()
    collision: Collision | None = None  # None: the file's own contact settings
    feet_are: str = "geom"  # "geom": each foot one collision geom; "subtree": a body and what hangs from it
    name: str = ""  # what the docs and the logs call it (default: the file's name)
    torso: str = ""  # the body whose tilt, roll and pitch rates and centre of mass the terms read ("": the base)
    foot_sites: tuple[str, ...] = ()  # the file's sites at the feet (): a site "<foot>_site" is added at each
    imu: str = "imu"  # the site the IMU's sensors read; added at the base's origin where the file has none
    self_collisions: bool = False  # its geoms collide with each other too, and a task feels it (a sensor on the base)
    touches: tuple[Touch, ...] = ()  # the geoms whose touches of the ground the rough task reads
    posture: dict = field(default_factory=dict)  # the pose reward's stds: {"standing"|"walking"|"running": std or
    #                                               {joint pattern: std}}; the rest ``warpgym.tasks.legged.robot_task``'s
    physics: dict = field(default_factory=dict)  # changes to ``PHYSICS`` the robot needs (the Go1: elliptic cones)
    package_root: str = ""  # where a URDF's ``package://NAME/...`` paths point: the package's folder or its parent
    balance_inertia: bool = False  # MuJoCo's compiler option balanceinertia (inertias that break A + B >= C)
    convex_decomposition: bool = False  # each non-convex collision mesh split into convex parts (convex.py, CoACD)
    task: dict = field(default_factory=dict)  # changes to the velocity task this robot walks in (LeggedTask.replace)

    @property
    def label(self) -> str:
        return self.name or os.path.splitext(os.path.basename(self.file))[0]

    @property
    def is_urdf(self) -> bool:
        return self.file.lower().endswith(".urdf")


def robot_spec(robot: RobotFile):
    """The robot's own spec from its file, its visual geoms and the meshes only they used removed, a free joint on
    its base, its collision policy applied."""
    import mujoco  # noqa: PLC0415

    if not os.path.isfile(robot.file):
        raise ValueError(f"robot file {robot.file!r} does not exist: give the MJCF or URDF file's path")
    if robot.is_urdf:
        from warpgym.tasks.legged.urdf import urdf_spec  # noqa: PLC0415

        spec = urdf_spec(robot.file, robot.package_root, robot.balance_inertia)
    else:
        spec = mujoco.MjSpec.from_file(robot.file)
        spec.compiler.balanceinertia = spec.compiler.balanceinertia or robot.balance_inertia
    bodies = [b.name for b in spec.bodies]
    if robot.root not in bodies:
        raise ValueError(f"{robot.file}: no body {robot.root!r} to be the base; its bodies are {bodies[1:]}")
    if robot.torso and robot.torso not in bodies:
        raise ValueError(f"{robot.file}: torso={robot.torso!r} is no body of it; its bodies are {bodies[1:]}")
    if robot.feet_are not in ("geom", "subtree"):
        raise ValueError(f"feet_are={robot.feet_are!r}: a foot is a collision 'geom' or a body's 'subtree'")
    if not robot.feet:
        raise ValueError(f"{robot.file}: feet=(): name the feet, collision geoms or bodies (feet_are='subtree')")
    # what drawing alone needs: a geom that collides with nothing and has no name (MuJoCo Menagerie's visual class)
    for geom in list(spec.geoms):
        if not geom.name and geom.contype == 0 and geom.conaffinity == 0:
            spec.delete(geom)
    _name_geoms(spec)
    have = {g.name for g in spec.geoms} if robot.feet_are == "geom" else set(bodies)
    missing = [f for f in robot.feet if f not in have]
    if missing:
        raise ValueError(f"{robot.file}: no foot {robot.feet_are}(s) {missing}; its named {robot.feet_are}s are "
                         f"{sorted(n for n in have if n)}")
    for actuator in list(spec.actuators):  # the file's own (a torque motor, say): the task's are position actuators
        spec.delete(actuator)
    for key in list(spec.keys):  # the scene's one keyframe is the standing pose
        spec.delete(key)
    used = {g.meshname for g in spec.geoms if g.type == mujoco.mjtGeom.mjGEOM_MESH}
    for mesh in list(spec.meshes):
        if mesh.name not in used:
            spec.delete(mesh)
    base = spec.body(robot.root)
    if not any(j.type == mujoco.mjtJoint.mjJNT_FREE for j in base.joints):
        if base.parent.name != "world":
            raise ValueError(f"{robot.file}: the base {robot.root!r} hangs from {base.parent.name!r}; name the "
                             "file's root body (a floating base is a child of the world)")
        base.add_freejoint(name="floating_base")
    if robot.collision is not None:
        _collide(spec, robot.collision)
    if not robot.self_collisions:  # the robot's geoms touch the ground (contype 1), never each other
        for geom in spec.geoms:
            if geom.contype or geom.conaffinity:
                geom.contype, geom.conaffinity = 2, 1
    if robot.convex_decomposition:
        from warpgym.tasks.legged.convex import decompose  # noqa: PLC0415

        decompose(spec, lambda copy: compile_robot_scene(copy, robot))
    _add_task_sensors(spec, robot)
    return spec


def _name_geoms(spec) -> None:
    """A name for each collision geom without one (a URDF's ``<collision>``): ``<body>_collision``, numbered from 1
    where a body has several, so that the collision policy, the feet and the touches can name them."""
    by_body: dict[str, list] = {}
    for geom in spec.geoms:
        if not geom.name:
            by_body.setdefault(geom.parent.name, []).append(geom)
    taken = {g.name for g in spec.geoms}
    for body, geoms in by_body.items():
        for i, geom in enumerate(geoms, 1):
            name = f"{body}_collision" + (str(i) if len(geoms) > 1 else "")
            while name in taken:
                name += "_"
            geom.name = name
            taken.add(name)


def _add_task_sensors(spec, robot: RobotFile) -> None:
    """The IMU (a site at the base with a gyro and a velocimeter), the base's subtree angular momentum and a site at
    each foot, where the file has none of its own (mjlab's robot files carry them)."""
    import mujoco  # noqa: PLC0415

    sites = {s.name for s in spec.sites}
    sensors = {s.name for s in spec.sensors}
    if robot.imu not in sites:
        spec.body(robot.root).add_site(name=robot.imu, group=5)
    for name, kind in (("imu_ang_vel", mujoco.mjtSensor.mjSENS_GYRO), ("imu_lin_vel", mujoco.mjtSensor.mjSENS_VELOCIMETER)):
        if name not in sensors:
            spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=robot.imu)
    if "root_angmom" not in sensors:
        spec.add_sensor(name="root_angmom", type=mujoco.mjtSensor.mjSENS_SUBTREEANGMOM,
                        objtype=mujoco.mjtObj.mjOBJ_BODY, objname=robot.root)
    if robot.foot_sites:
        missing = [s for s in robot.foot_sites if s not in sites]
        if missing or len(robot.foot_sites) != len(robot.feet):
            raise ValueError(f"{robot.file}: foot_sites={list(robot.foot_sites)}: give one site of the file per foot "
                             f"({len(robot.feet)}), or none to have them added; its sites are {sorted(sites)}")
        return
    geoms = {g.name: g for g in spec.geoms}
    for foot in robot.feet:
        if robot.feet_are == "geom":
            geom = geoms[foot]
            geom.parent.add_site(name=f"{foot}_site", pos=list(geom.pos), group=5)
        else:
            spec.body(foot).add_site(name=f"{foot}_site", group=5)


def foot_sites(robot: RobotFile) -> tuple[str, ...]:
    """The feet's sites as the built scene names them, without the prefix."""
    return tuple(robot.foot_sites) or tuple(f"{f}_site" for f in robot.feet)


def _collide(spec, policy: Collision) -> None:
    for geom in spec.geoms:
        if not matches(policy.geoms, geom.name):
            geom.contype = geom.conaffinity = 0
            continue
        where = f"collision of {geom.name!r}"
        geom.contype = int(first_match(policy.contype, geom.name, where))
        geom.conaffinity = int(first_match(policy.conaffinity, geom.name, where))
        geom.condim = int(first_match(policy.condim, geom.name, where))
        geom.priority = int(first_match(policy.priority, geom.name, where))
        for name in ("friction", "solref", "solimp"):
            value = getattr(policy, name)
            value = first_match(value, geom.name, where, default=None) if isinstance(value, dict) else value
            if value is not None:
                target = getattr(geom, name)
                target[: len(value)] = value


def build_scene(robot: RobotFile, physics: dict | None = None, floor: bool = True, self_collision: bool = False,
                touches: tuple = ()):
    """A velocity task's scene as an ``MjSpec``: MuJoCo's options (``PHYSICS``, changed by ``physics``), a body
    ``terrain`` (with a floor plane, or empty for the generated ground to fill), the robot under ``robot/``, its
    actuators, the standing keyframe; lit and coloured as mjlab's scenes are. Its contact sensors, in mjlab's order:
    each foot's with the ground (``feet_ground_contact_<foot>_found`` and ``_force``, the net force), the robot's
    with itself (``self_collision``: ``self_collision_<root>_...``), and each group of ``touches``, ``(name, geom
    patterns)``, a sensor of each matching geom with the ground (``<name>_<geom>_...``)."""
    import mujoco  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415

    scene = mujoco.MjSpec()
    scene.modelname = "mjlab scene"
    scene.compiler.degree = False
    _physics(scene, {**PHYSICS, **dict(robot.physics), **(physics or {})})
    _look(scene)
    scene.worldbody.add_light(name="sun", pos=[0, 0, 1.5], dir=[0, 0, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    terrain = scene.worldbody.add_body(name="terrain")
    if floor:
        terrain.add_geom(name="terrain", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.01], material="groundplane")
    part = robot_spec(robot)
    joints = [j for j in part.joints if j.type != mujoco.mjtJoint.mjJNT_FREE]
    chosen = _add_actuators(part, robot, joints)
    geom_names = [g.name for g in part.geoms]  # before the attach prefixes them
    # the standing pose, read before the attach renames the joints
    pose = {j.name: float(first_match(dict(robot.joint_pos), j.name, "joint_pos", default=0.0)) for j in joints}
    height = robot.base_height if robot.base_height is not None else standing_height(robot, part, pose)
    qpos = [0.0, 0.0, height, 1.0, 0.0, 0.0, 0.0] + [pose[j.name] for j in joints]
    ctrl = [pose[name] for name in chosen]
    # the scene's options are the task's: the file's own (a timestep, a solver) give way without a warning
    _physics(part, {**PHYSICS, **dict(robot.physics), **(physics or {})})
    part.option.solver, part.nuser_geom, part.nkey = scene.option.solver, scene.nuser_geom, scene.nkey
    scene.attach(part, prefix=PREFIX, frame=scene.worldbody.add_frame())
    found, force = (1 << int(f) for f in (mujoco.mjtConDataField.mjCONDATA_FOUND, mujoco.mjtConDataField.mjCONDATA_FORCE))
    kind = mujoco.mjtObj.mjOBJ_GEOM if robot.feet_are == "geom" else mujoco.mjtObj.mjOBJ_XBODY
    for foot in robot.feet:
        for data, tag in ((found, "found"), (force, "force")):
            _contact_sensor(scene, f"feet_ground_contact_{foot}_{tag}", kind, PREFIX + foot, mujoco.mjtObj.mjOBJ_BODY,
                            "terrain", data, NETFORCE)
    if self_collision:
        for data, tag in ((found, "found"), (force, "force")):
            _contact_sensor(scene, f"self_collision_{robot.root}_{tag}", mujoco.mjtObj.mjOBJ_XBODY, PREFIX + robot.root,
                            mujoco.mjtObj.mjOBJ_XBODY, PREFIX + robot.root, data, 0)
    for name, patterns in touches:
        hits = [g for g in geom_names if matches(patterns, g)]
        if not hits:
            raise ValueError(f"touches {name!r}: no geom of {robot.file} matches {list(patterns)}; its named geoms are "
                             f"{[g for g in geom_names if g]}")
        for geom in hits:
            for data, tag in ((found, "found"), (force, "force")):
                _contact_sensor(scene, f"{name}_{geom}_{tag}", mujoco.mjtObj.mjOBJ_GEOM, PREFIX + geom,
                                mujoco.mjtObj.mjOBJ_BODY, "terrain", data, 0)
    scene.add_key(name="init_state", qpos=np.array(qpos), ctrl=np.array(ctrl))
    return scene


def standing_height(robot: RobotFile, part, pose: dict) -> float:
    """The base's height at which the feet's lowest point (a sphere's, else the bounding box's of each foot geom or of
    a foot body's collision geoms) is ``CLEARANCE`` above the floor, the joints at ``pose``."""
    import mujoco  # noqa: PLC0415
    import numpy as np  # noqa: PLC0415

    m = compile_robot_scene(part.copy(), robot)
    d = mujoco.MjData(m)
    for name, angle in pose.items():
        d.qpos[m.jnt_qposadr[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)]] = angle
    root = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, robot.root)
    free = next(j for j in range(m.njnt) if m.jnt_bodyid[j] == root and m.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE)
    d.qpos[m.jnt_qposadr[free]:m.jnt_qposadr[free] + 7] = [0, 0, 0, 1, 0, 0, 0]
    mujoco.mj_kinematics(m, d)
    if robot.feet_are == "geom":
        geoms = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f) for f in robot.feet]
    else:
        feet = {mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f) for f in robot.feet}
        under = lambda b: b in feet or (b > 0 and under(int(m.body_parentid[b])))  # noqa: E731
        geoms = [g for g in range(m.ngeom) if under(int(m.geom_bodyid[g])) and (m.geom_contype[g] or m.geom_conaffinity[g])]
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)

    def bottom(g):  # a sphere's lowest point, else its box's (MuJoCo's geom_aabb: centre and half-sizes)
        if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_SPHERE:
            return d.geom_xpos[g, 2] - m.geom_size[g, 0]
        centre, half = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
        points = (centre + corners * half) @ d.geom_xmat[g].reshape(3, 3).T + d.geom_xpos[g]
        return points[:, 2].min()

    # 1 mm above the floor: feet exactly on it would make the first contact a tie between float32 and float64
    return float(CLEARANCE - min(bottom(g) for g in geoms)) if geoms else float(np.nan)


def _add_actuators(part, robot: RobotFile, joints) -> list[str]:
    """A position actuator per joint an ``Actuator`` names, group by group (mjlab's order); returns their joints."""
    import mujoco  # noqa: PLC0415

    chosen: list[str] = []
    for act in robot.actuators:
        hits = [j for j in joints if matches(act.patterns, j.name)]
        if not hits:
            raise ValueError(f"actuator {act.joints!r} matches no joint of {robot.file}; its joints are "
                             f"{[j.name for j in joints]}")
        kp, kd = act.gains()
        for joint in hits:
            if joint.name in chosen:
                raise ValueError(f"joint {joint.name!r} matches two actuators: make their patterns exclusive")
            chosen.append(joint.name)
            if act.armature is not None:
                joint.armature = act.armature
            effort = act.effort_limit if act.effort_limit is not None else float(joint.actfrcrange[1])
            if not effort > 0:
                raise ValueError(f"actuator {act.joints!r}: joint {joint.name!r} has no effort limit in "
                                 f"{robot.file}: give the actuator an effort_limit [N m]")
            a = part.add_actuator(name=joint.name, target=joint.name)
            a.trntype = mujoco.mjtTrn.mjTRN_JOINT
            a.gaintype, a.biastype = mujoco.mjtGain.mjGAIN_FIXED, mujoco.mjtBias.mjBIAS_AFFINE
            a.gainprm[0], a.biasprm[1], a.biasprm[2] = kp, -kp, -kd
            # targets beyond the joint's range are the policy's to give (mjlab's position actuators): only the
            # force is bounded, the control range says where it saturates
            a.inheritrange, a.ctrllimited, a.forcelimited = 0.0, False, True
            a.forcerange[:] = [-effort, effort]
            low, high = (math.radians(v) for v in joint.range) if part.compiler.degree else joint.range
            a.ctrlrange[:] = [low - effort / kp, high + effort / kp]
    if not chosen:
        raise ValueError(f"{robot.file}: no actuators: give RobotFile.actuators, a pattern of joints each")
    return chosen


def _physics(scene, physics: dict) -> None:
    import mujoco  # noqa: PLC0415

    unknown = sorted(set(physics) - set(PHYSICS))
    if unknown:
        raise ValueError(f"physics {unknown}: the options a scene takes are {sorted(PHYSICS)}")
    opt = scene.option
    opt.timestep, opt.impratio = float(physics["timestep"]), float(physics["impratio"])
    opt.iterations, opt.ls_iterations = int(physics["iterations"]), int(physics["ls_iterations"])
    opt.ccd_iterations = int(physics["ccd_iterations"])
    opt.integrator = getattr(mujoco.mjtIntegrator, f"mjINT_{physics['integrator'].upper()}")
    opt.cone = getattr(mujoco.mjtCone, f"mjCONE_{physics['cone'].upper()}")


def _look(scene) -> None:
    """mjlab's scene.xml's view and its checkered floor: for drawings, nothing the physics reads."""
    import mujoco  # noqa: PLC0415

    v = scene.visual
    v.headlight.ambient, v.headlight.diffuse, v.headlight.specular = [0.3] * 3, [0.6] * 3, [0.0] * 3
    v.rgba.force, v.rgba.haze = [1, 0, 0, 1], [0.15, 0.25, 0.35, 1]
    v.global_.azimuth, v.global_.elevation, v.global_.offwidth, v.global_.offheight = 135, -25, 1920, 1080
    v.map.force = 0.005
    v.scale.forcewidth, v.scale.contactwidth, v.scale.contactheight = 0.25, 0.4, 0.15
    v.scale.framelength, v.scale.framewidth = 5.0, 0.3
    v.quality.shadowsize = 8192
    scene.stat.meansize, scene.stat.extent = 0.03, 2.0
    scene.add_texture(name="groundplane", type=mujoco.mjtTexture.mjTEXTURE_2D, builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER,
                      mark=mujoco.mjtMark.mjMARK_EDGE, rgb1=[0.2, 0.3, 0.4], rgb2=[0.1, 0.2, 0.3],
                      markrgb=[0.8, 0.8, 0.8], width=300, height=300)
    mat = scene.add_material(name="groundplane", texuniform=True, texrepeat=[4, 4], reflectance=0.2)
    mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "groundplane"


def _contact_sensor(scene, name: str, objtype, objname: str, reftype, refname: str, data: int, reduce: int) -> None:
    """A contact sensor of one match (MuJoCo's ``intprm``: the data fields' bits, the reduction, the matches)."""
    import mujoco  # noqa: PLC0415

    s = scene.add_sensor(name=name, type=mujoco.mjtSensor.mjSENS_CONTACT, objtype=objtype, objname=objname,
                         reftype=reftype, refname=refname)
    s.intprm[0], s.intprm[1], s.intprm[2] = data, reduce, 1


def compile_robot_scene(spec, robot: RobotFile):
    """MuJoCo's compile of a scene ``build_scene`` made, its refusals one line naming the file and the fix."""
    try:
        return spec.compile()
    except ValueError as e:
        why = " ".join(str(e).split())
        if "balanceinertia" in why:
            raise ValueError(f"{robot.file}: MuJoCo rejects an inertia of it ({why}): set balance_inertia = true in "
                             "the robot's definition (MuJoCo's compiler option balanceinertia)") from None
        if "Error opening file" in why or "resource not found" in why.lower():
            raise ValueError(f"{robot.file}: a file it names is missing ({why}): put the mesh beside the robot's "
                             "file or set package_root") from None
        raise ValueError(f"{robot.file}: MuJoCo cannot compile the robot's scene: {why}") from None
