"""warpgym's own Ant and Humanoid (the robots Newton simulates): which MJCF file, where they start, which bodies
are feet. (Gymnasium's tasks and the legged robots are models of their own projects' files: ``warpgym.tasks``.)

The MJCF files are the ones Newton ships (``newton.examples.get_asset``). Their motor gears are
read straight from the ``<actuator>`` block so that there is one source for them: the file.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from dataclasses import dataclass


@dataclass(frozen=True)
class RobotSpec:
    name: str
    mjcf: str
    # Height of the root body at reset [m]; chosen so the feet clear the ground under the
    # largest joint-position noise a reset can draw.
    start_height: float
    # Body names (last path component of Newton's body label) whose contact wrench is observed.
    feet: tuple[str, ...]
    # MuJoCo Warp buffer sizes per world (contacts, constraint rows). None: Newton's estimate from the
    # start pose, which is too small for a robot lying on the ground tangled in itself: a world that
    # needs more rows loses constraints for that substep (counted in Sim.solver_overflows).
    nconmax: int | None = None
    njmax: int | None = None
    # Device memory per 1000 envs [MiB], measured on an H100 (docs/benchmarks.md), for the check
    # that refuses a num_envs the GPU cannot hold before anything is allocated.
    mib_per_1000_envs: float = 50.0


ROBOTS: dict[str, RobotSpec] = {
    "ant": RobotSpec(
        name="ant",
        mjcf="nv_ant.xml",
        start_height=0.55,
        feet=("front_left_foot", "front_right_foot", "left_back_foot", "right_back_foot"),
        # Newton's estimate (64 rows) overflowed in fast training runs. With the ground alone the Ant
        # has at most 25 contacts (the torso sphere 1, 12 capsules 2 each) of 4 pyramid rows, plus 8
        # joint limits: 108 rows; contacts between its own legs would add to that. A 5-minute
        # training run peaked at 69 (docs/benchmarks.md).
        njmax=128,
        # Not measured with njmax 128: bench.py read 89 MiB per 1000 envs with 64 (a process's first
        # model, Warp's memory pools included) and 56 with 128 (its second model, pools reused).
        mib_per_1000_envs=90.0,
    ),
    "humanoid": RobotSpec(
        name="humanoid",
        mjcf="nv_humanoid.xml",
        start_height=1.34,
        feet=("right_foot", "left_foot"),
        nconmax=96,
        njmax=192,
        mib_per_1000_envs=110.0,
    ),
}


def robot_spec(name: str) -> RobotSpec:
    key = str(name).lower()
    if key not in ROBOTS:
        raise ValueError(f"unknown robot {name!r}: choose one of {sorted(ROBOTS)}")
    return ROBOTS[key]


def mjcf_path(spec: RobotSpec) -> str:
    # Read the asset from Newton's package data without importing newton.examples, which pulls
    # in Newton's test utilities (absent from trimmed installs).
    import importlib.util  # noqa: PLC0415
    import os  # noqa: PLC0415

    origin = importlib.util.find_spec("newton").origin
    path = os.path.join(os.path.dirname(origin), "examples", "assets", spec.mjcf)
    if not os.path.isfile(path):
        raise FileNotFoundError(f"{spec.mjcf} is not in this Newton install ({path}); reinstall newton[sim]")
    return path


def motor_gears(path: str) -> dict[str, float]:
    """Joint name -> motor gear, from the MJCF's ``<actuator><motor joint=.. gear=..>`` entries."""
    root = ET.parse(path).getroot()
    gears: dict[str, float] = {}
    for motor in root.iter("motor"):
        joint = motor.get("joint")
        if joint is None:
            continue
        gears[joint] = float(motor.get("gear", "1").split()[0])
    return gears


def hinge_joint_names(path: str) -> list[str]:
    """Names of the MJCF's hinge joints in document order, which is Newton's dof order."""
    root = ET.parse(path).getroot()
    return [j.get("name") for j in root.find("worldbody").iter("joint") if j.get("type", "hinge") == "hinge"]
