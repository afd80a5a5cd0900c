"""A legged robot from its own MJCF file: the scene a velocity task steps, built with MuJoCo's MjSpec from the file and
a few numbers, the way mjlab's entity and scene configs build theirs.

A ``RobotFile`` names the file, the root body, the feet (collision geoms, or bodies' subtrees), the standing pose,
the actuators (PD position targets: stiffness and damping given, or derived from the reflected inertia, a natural
frequency and a damping ratio) and what collides. ``build_scene`` attaches the robot under the ``robot/`` prefix
beside a body named ``terrain`` (a floor, or empty for the generated ground), keeps its collision geometry (visual
meshes are dropped: the scene is for stepping), applies the collision policy, adds a position actuator per actuated
joint and the contact sensors the task reads, and writes the standing pose as the keyframe. MuJoCo's compile of the
result is the model; tests/test_robot_file.py checks the Go1's and the G1's against the scenes committed from
mjlab's environment, field by field.
"""

from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass, field

PREFIX = "robot/"
NETFORCE = 3  # a contact sensor's reduction to the net force of its matches (MuJoCo's mjtConDataReduce; no Python enum)


# MuJoCo's options of mjlab's velocity tasks (its SimulationCfg; the Go1's task changes the cone and impratio)
PHYSICS = {"timestep": 0.005, "integrator": "implicitfast", "cone": "pyramidal", "impratio": 1.0, "iterations": 10,
           "ls_iterations": 20, "ccd_iterations": 50}


@dataclass(frozen=True)
class Actuator:
    """Position actuators on the joints whose names match ``joints`` (a regular expression matched in full), in the
    file's joint order. ``stiffness``/``damping`` [N m/rad, N m s/rad] given, or derived from ``armature`` (the
    reflected inertia, kg m^2) as mjlab derives them: stiffness = armature * w^2, damping = 2 * ratio * armature * w,
    w = 2 pi * ``natural_frequency`` [Hz]. ``armature`` is also the joints' armature; ``effort_limit`` [N m] bounds
    the force."""

    joints: str | tuple[str, ...]  # one pattern or several
    effort_limit: float
    armature: float = 0.0
    stiffness: float | None = None
    damping: float | None = None
    natural_frequency: float | None = None
    damping_ratio: float | None = None

    def gains(self) -> tuple[float, float]:
        if self.stiffness is not None and self.damping is not None:
            return float(self.stiffness), float(self.damping)
        if self.natural_frequency is None or self.damping_ratio is None or not self.armature > 0:
            raise ValueError(f"actuator {self.joints!r}: give stiffness and damping, or an armature > 0 with a "
                             "natural_frequency [Hz] and a damping_ratio to derive them from")
        w = 2.0 * math.pi * self.natural_frequency
        return self.armature * w * w, 2.0 * self.damping_ratio * self.armature * w


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
class RobotFile:
    """A legged robot's MJCF file and what the velocity tasks need to know of it."""

    file: str
    root: str  # the floating base's body
    feet: tuple[str, ...]  # the feet, in the task's foot order: collision geoms, or bodies (``feet_are="subtree"``)
    base_height: float  # the standing pose's base height [m]
    joint_pos: dict = field(default_factory=dict)  # {joint pattern: angle [rad]}; joints no pattern names stand at 0
    actuators: tuple[Actuator, ...] = ()
    collision: Collision | None = None  # None: the file's own contact settings
    feet_are: str = "geom"  # "geom": each foot one collision geom; "subtree": a body and what hangs from it

    def __hash__(self):
        return hash((self.file, self.root, self.feet, self.base_height, tuple(self.joint_pos.items())))


def _full(pattern: str, name: str) -> bool:
    return re.fullmatch(pattern, name) is not None


def _pick(value, name: str, where: str):
    """``value`` for the geom or joint ``name``: the value itself, or a dict's first pattern that matches."""
    if not isinstance(value, dict):
        return value
    for pattern, v in value.items():
        if _full(pattern, name):
            return v
    raise ValueError(f"{where}: no pattern of {list(value)} matches {name!r}: add one (a catch-all '.*' serves)")


def robot_spec(robot: RobotFile):
    """The robot's own spec from its file, its visual geoms and the meshes only they used removed, its collision
    policy applied."""
    import mujoco  # noqa: PLC0415

    if not os.path.isfile(robot.file):
        raise ValueError(f"robot file {robot.file!r} does not exist: give the MJCF file's path")
    spec = mujoco.MjSpec.from_file(robot.file)
    bodies = [b.name for b in spec.bodies]
    if robot.root not in bodies:
        raise ValueError(f"{robot.file}: no body {robot.root!r} to be the base; its bodies are {bodies[1:]}")
    if robot.feet_are not in ("geom", "subtree"):
        raise ValueError(f"feet_are={robot.feet_are!r}: a foot is a collision 'geom' or a body's 'subtree'")
    have = {g.name for g in spec.geoms} if robot.feet_are == "geom" else set(bodies)
    missing = [f for f in robot.feet if f not in have]
    if missing:
        raise ValueError(f"{robot.file}: no foot {robot.feet_are}(s) {missing}; its named {robot.feet_are}s are "
                         f"{sorted(n for n in have if n)}")
    # what drawing alone needs: a geom that collides with nothing and has no name (MuJoCo Menagerie's visual class)
    for geom in list(spec.geoms):
        if not geom.name and geom.contype == 0 and geom.conaffinity == 0:
            spec.delete(geom)
    used = {g.meshname for g in spec.geoms if g.type == mujoco.mjtGeom.mjGEOM_MESH}
    for mesh in list(spec.meshes):
        if mesh.name not in used:
            spec.delete(mesh)
    if robot.collision is not None:
        _collide(spec, robot.collision)
    return spec


def _collide(spec, policy: Collision) -> None:
    for geom in spec.geoms:
        if not any(_full(p, geom.name) for p in policy.geoms):
            geom.contype = geom.conaffinity = 0
            continue
        where = f"collision of {geom.name!r}"
        geom.contype = int(_pick(policy.contype, geom.name, where))
        geom.conaffinity = int(_pick(policy.conaffinity, geom.name, where))
        geom.condim = int(_pick(policy.condim, geom.name, where))
        geom.priority = int(_pick(policy.priority, geom.name, where))
        for name in ("friction", "solref", "solimp"):
            value = getattr(policy, name)
            if isinstance(value, dict):
                value = next((v for p, v in value.items() if _full(p, geom.name)), None)
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
    _physics(scene, {**PHYSICS, **(physics or {})})
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
    pose = {j.name: float(next((v for p, v in robot.joint_pos.items() if _full(p, j.name)), 0.0)) for j in joints}
    qpos = [0.0, 0.0, robot.base_height, 1.0, 0.0, 0.0, 0.0] + [pose[j.name] for j in joints]
    ctrl = [pose[name] for name in chosen]
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
        hits = [g for g in geom_names if any(_full(p, g) for p in patterns)]
        if not hits:
            raise ValueError(f"touches {name!r}: no geom of {robot.file} matches {list(patterns)}; its named geoms are "
                             f"{[g for g in geom_names if g]}")
        for geom in hits:
            for data, tag in ((found, "found"), (force, "force")):
                _contact_sensor(scene, f"{name}_{geom}_{tag}", mujoco.mjtObj.mjOBJ_GEOM, PREFIX + geom,
                                mujoco.mjtObj.mjOBJ_BODY, "terrain", data, 0)
    scene.add_key(name="init_state", qpos=np.array(qpos), ctrl=np.array(ctrl))
    return scene


def _add_actuators(part, robot: RobotFile, joints) -> list[str]:
    """A position actuator per joint an ``Actuator`` names, group by group (mjlab's order); returns their joints."""
    import mujoco  # noqa: PLC0415

    chosen: list[str] = []
    for act in robot.actuators:
        patterns = (act.joints,) if isinstance(act.joints, str) else tuple(act.joints)
        hits = [j for j in joints if any(_full(p, j.name) for p in patterns)]
        if not hits:
            raise ValueError(f"actuator {act.joints!r} matches no joint of {robot.file}; its joints are "
                             f"{[j.name for j in joints]}")
        kp, kd = act.gains()
        for joint in hits:
            if joint.name in chosen:
                raise ValueError(f"joint {joint.name!r} matches two actuators: make their patterns exclusive")
            chosen.append(joint.name)
            joint.armature = act.armature
            a = part.add_actuator(name=joint.name, target=joint.name)
            a.trntype = mujoco.mjtTrn.mjTRN_JOINT
            a.gaintype, a.biastype = mujoco.mjtGain.mjGAIN_FIXED, mujoco.mjtBias.mjBIAS_AFFINE
            a.gainprm[0], a.biasprm[1], a.biasprm[2] = kp, -kp, -kd
            # targets beyond the joint's range are the policy's to give (mjlab's position actuators): only the
            # force is bounded, the control range says where it saturates
            a.inheritrange, a.ctrllimited, a.forcelimited = 0.0, False, True
            a.forcerange[:] = [-act.effort_limit, act.effort_limit]
            low, high = joint.range
            a.ctrlrange[:] = [low - act.effort_limit / kp, high + act.effort_limit / kp]
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
