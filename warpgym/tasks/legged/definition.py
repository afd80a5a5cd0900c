"""A robot's definition as a TOML file: the fields of ``robot_file.RobotFile``, its actuators and touches as arrays of
tables, its collision policy as a table. TOML because Python reads it without a dependency (``tomllib``), it holds
only data (nothing in it runs), and it is what ``pyproject.toml`` taught this ecosystem; a wrong key or value is one
line naming it and the keys there are.

Paths (``file``, ``package_root``) are relative to the definition's folder, or, with ``data_package = "NAME"``, to
that installed package's folder (``pybullet_data``: the zoo's URDFs, ``pip install 'warpgym[zoo]'``).

    file = "my_robot.urdf"
    root = "base"
    feet = ["FL_foot_collision", "FR_foot_collision", "RL_foot_collision", "RR_foot_collision"]
    [joint_pos]
    ".*_thigh" = 0.8
    [[actuators]]
    joints = ".*"
    stiffness = 20.0
    damping = 0.5
"""

from __future__ import annotations

import importlib.util
import os
import tomllib
from dataclasses import fields

from warpgym.tasks.legged.robot_file import Actuator, Collision, RobotFile, Touch

TUPLES = {"feet", "foot_sites", "geoms", "joints", "friction", "solref", "solimp"}


def _known(cls) -> list[str]:
    return [f.name for f in fields(cls)]


def _make(cls, table, where: str, path: str):
    if not isinstance(table, dict):
        raise ValueError(f"{path}: {where} must be a table of {cls.__name__}'s keys {_known(cls)}")
    unknown = sorted(set(table) - set(_known(cls)))
    if unknown:
        raise ValueError(f"{path}: {where} has no key(s) {unknown}; its keys are {_known(cls)}")
    values = {k: (tuple(v) if k in TUPLES and isinstance(v, list) else v) for k, v in table.items()}
    try:
        return cls(**values)
    except TypeError as e:
        raise ValueError(f"{path}: {where}: {e}") from None


def data_folder(package: str, path: str) -> str:
    """The folder of an installed data package, found without importing it."""
    spec = importlib.util.find_spec(package) if package.isidentifier() else None
    if spec is None or not spec.submodule_search_locations:
        extra = " (pip install 'warpgym[zoo]')" if package == "pybullet_data" else ""
        raise ValueError(f"{path}: data_package={package!r} is not installed{extra}: install it, or give the file's "
                         "path relative to the definition")
    return list(spec.submodule_search_locations)[0]


def load_definition(path: str) -> RobotFile:
    """The ``RobotFile`` a TOML definition describes."""
    if not os.path.isfile(path):
        raise ValueError(f"robot definition {path!r} does not exist: give a TOML file's path")
    try:
        with open(path, "rb") as f:
            data = tomllib.load(f)
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: not valid TOML ({e}): fix the line it names") from None
    keys = set(_known(RobotFile)) | {"data_package"}
    unknown = sorted(set(data) - keys)
    if unknown:
        raise ValueError(f"{path}: no key(s) {unknown} in a robot's definition; its keys are {sorted(keys)}")
    missing = [k for k in ("file", "root", "feet", "actuators") if k not in data]
    if missing:
        raise ValueError(f"{path}: a robot's definition needs {missing}")
    folder = os.path.dirname(os.path.abspath(path))
    if "data_package" in data:
        folder = data_folder(str(data.pop("data_package")), path)
    for key in ("file", "package_root"):
        if data.get(key):
            data[key] = os.path.normpath(os.path.join(folder, os.path.expanduser(str(data[key]))))
    if not isinstance(data["actuators"], list) or not data["actuators"]:
        raise ValueError(f"{path}: actuators must be an array of tables ([[actuators]] with joints = pattern, and "
                         "stiffness and damping, or armature, natural_frequency and damping_ratio)")
    data["actuators"] = tuple(_make(Actuator, a, f"actuators[{i}]", path) for i, a in enumerate(data["actuators"]))
    if "collision" in data:
        data["collision"] = _make(Collision, data["collision"], "[collision]", path)
    if "touches" in data:
        data["touches"] = tuple(_make(Touch, t, f"touches[{i}]", path) for i, t in enumerate(data["touches"]))
    robot = _make(RobotFile, data, "the definition", path)
    if robot.base_height is not None and (not isinstance(robot.base_height, (int, float)) or not robot.base_height > 0):
        raise ValueError(f"{path}: base_height={robot.base_height!r} must be the standing base's height > 0 [m]")
    return robot
