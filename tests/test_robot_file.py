"""A legged robot's scene built from its own MJCF file (warpgym.tasks.legged.robot_file): the Go1's and the G1's,
from the raw files of mjlab's asset zoo (committed without their meshes) and the numbers of its configs, are MuJoCo's
compile of the committed scenes field by field; a small robot of the test's own checks the derived gains, the
standing keyframe and the refusals."""

import importlib.util
import os

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from warpgym.tasks.legged.robot_file import Actuator, Collision, RobotFile, build_scene  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASSETS = os.path.join(ROOT, "warpgym", "tasks", "legged", "assets")


def mjlab_zoo() -> str | None:
    """mjlab's ``asset_zoo/robots`` folder: ``WARPGYM_MJLAB_ROBOTS`` (CI points it into mjlab's own environment), or
    an installed mjlab's (found without importing it)."""
    if os.environ.get("WARPGYM_MJLAB_ROBOTS"):
        return os.environ["WARPGYM_MJLAB_ROBOTS"]
    spec = importlib.util.find_spec("mjlab")
    return os.path.join(os.path.dirname(spec.origin), "asset_zoo", "robots") if spec and spec.origin else None


def differences(ref, built) -> list[str]:
    """Every array of MuJoCo's model, its options, view and statistics, and the names, that differ."""
    out = []
    for name in dir(ref):
        a = getattr(ref, name, None)
        if name.startswith("_") or not isinstance(a, np.ndarray):
            continue
        b = getattr(built, name)
        if a.shape != b.shape:
            out.append(f"{name}: shape {a.shape} against {b.shape}")
        elif name.startswith(("name_", "names")):
            continue
        elif a.size and not np.allclose(a, b, rtol=1e-5, atol=1e-6):  # the committed file rounds to 6 digits
            out.append(f"{name}: differs by up to {np.abs(a.astype(float) - b.astype(float)).max():.3g}")
    for group in ("opt", "vis", "stat"):
        out += [f"{group}.{n}" for n in struct_fields(getattr(ref, group), getattr(built, group))]
    for kind in (mujoco.mjtObj.mjOBJ_BODY, mujoco.mjtObj.mjOBJ_JOINT, mujoco.mjtObj.mjOBJ_GEOM,
                 mujoco.mjtObj.mjOBJ_SITE, mujoco.mjtObj.mjOBJ_ACTUATOR, mujoco.mjtObj.mjOBJ_SENSOR):
        count = {mujoco.mjtObj.mjOBJ_BODY: "nbody", mujoco.mjtObj.mjOBJ_JOINT: "njnt", mujoco.mjtObj.mjOBJ_GEOM: "ngeom",
                 mujoco.mjtObj.mjOBJ_SITE: "nsite", mujoco.mjtObj.mjOBJ_ACTUATOR: "nu",
                 mujoco.mjtObj.mjOBJ_SENSOR: "nsensor"}[kind]
        names = [[mujoco.mj_id2name(m, kind, i) for i in range(getattr(m, count))] for m in (ref, built)]
        if names[0] != names[1]:
            out.append(f"{count} names: {sorted(set(names[0]) ^ set(names[1]))[:6]} or their order")
    return out


def struct_fields(a, b, prefix="") -> list[str]:
    out = []
    for n in dir(a):
        x = getattr(a, n)
        if n.startswith("_") or callable(x):
            continue
        if isinstance(x, (int, float, np.ndarray)):
            if not np.allclose(np.asarray(x, float), np.asarray(getattr(b, n), float), rtol=1e-5, atol=1e-7):
                out.append(f"{prefix}{n}: {x} against {getattr(b, n)}")
        else:
            out += struct_fields(x, getattr(b, n), f"{prefix}{n}.")
    return out


@pytest.mark.parametrize("task", ["Go1VelocityFlat-v0", "G1VelocityFlat-v0", "Go1VelocityRough-v0",
                                  "G1VelocityRough-v0"])
def test_the_tasks_build_the_scenes_exported_from_mjlab_from_the_robots_own_files(task):
    """The four tasks' scenes come from the builder (the robot's own file, committed without its meshes, and its
    definition; the task's options, ground and contact sensors): MuJoCo's compile of each equals the scene exported
    from mjlab's env (assets/<task>.xml, the check), the rough ones on the same generated ground."""
    import dataclasses

    from warpgym.sim.scene import compile_scene
    from warpgym.tasks.legged import LEGGED
    from warpgym.tasks.legged.model import compile_task_scene, task_scene
    from warpgym.tasks.legged.terrain import add_to_spec

    spec = LEGGED[task]
    built, ground = compile_task_scene(spec)
    exported = os.path.join(ASSETS, spec.name.replace("Velocity", "_velocity_").replace("-v0", "").lower() + ".xml")
    ref = compile_scene(exported, None if ground is None else lambda s: add_to_spec(s, ground)).mjm
    assert built.path == spec.robot.file and differences(ref, built.mjm) == []
    # what a difference would look like: one actuator's effort limit
    robot = spec.robot
    weaker = dataclasses.replace(robot, actuators=(dataclasses.replace(robot.actuators[0], effort_limit=20.0),
                                                   *robot.actuators[1:]))
    other = task_scene(dataclasses.replace(spec, robot=weaker))
    if ground is not None:
        add_to_spec(other, ground)
    assert any(d.startswith("actuator_forcerange") for d in differences(ref, other.compile()))


@pytest.mark.parametrize("robot", ["go1", "g1"])
def test_the_committed_robot_files_are_mjlabs_asset_zoos(robot):
    """assets/unitree_<robot>.xml is the file mjlab's wheel ships, but for its first line (CI's mjlab stage)."""
    zoo = mjlab_zoo()
    if zoo is None or not os.path.isdir(zoo):
        pytest.skip("mjlab's asset zoo is not here (CI's mjlab stage sets WARPGYM_MJLAB_ROBOTS)")
    ours = open(os.path.join(ASSETS, f"unitree_{robot}.xml")).read().split("\n", 1)
    assert ours[0].startswith("<!-- MuJoCo Menagerie's Unitree")
    assert ours[1] == open(os.path.join(zoo, f"unitree_{robot}", "xmls", f"{robot}.xml")).read()


TOY = """<mujoco model="toy">
  <worldbody>
    <body name="base" pos="0 0 0.5">
      <freejoint name="root"/>
      <geom name="base_collision" type="box" size="0.1 0.05 0.05" mass="2"/>
      <geom type="box" size="0.11 0.06 0.06" contype="0" conaffinity="0" group="2"/>
      <body name="leg" pos="0 0 -0.05">
        <joint name="hip" axis="0 1 0" range="-1 1"/>
        <geom name="leg_collision" type="capsule" fromto="0 0 0 0 0 -0.2" size="0.02" mass="0.3"/>
        <body name="shin" pos="0 0 -0.2">
          <joint name="knee" axis="0 1 0" range="-2 0"/>
          <geom name="foot_collision" type="sphere" pos="0 0 -0.2" size="0.025" mass="0.1"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


@pytest.fixture
def toy(tmp_path):
    path = tmp_path / "toy.xml"
    path.write_text(TOY)
    return RobotFile(str(path), root="base", feet=("foot_collision",), base_height=0.42,
                     joint_pos={"knee": -0.6}, actuators=(Actuator("hip|knee", 10.0, 0.01, natural_frequency=5.0,
                                                                   damping_ratio=1.5),),
                     collision=Collision((".*_collision",), condim={"foot_collision": 6, ".*": 1}))


def test_gains_come_from_the_reflected_inertia_and_the_pose_from_the_definition(toy):
    m = build_scene(toy).compile()
    w = 2 * np.pi * 5.0
    kp, kd = 0.01 * w * w, 2 * 1.5 * 0.01 * w
    np.testing.assert_allclose(m.actuator_gainprm[:, 0], kp, rtol=1e-6)
    np.testing.assert_allclose(m.actuator_biasprm[:, :3], [[0, -kp, -kd]] * 2, rtol=1e-6)
    np.testing.assert_allclose(m.dof_armature[6:], 0.01)
    # the control range is where the force saturates at the joint's limits: range -+ effort / stiffness (the toy's
    # ranges are in MJCF's default degrees)
    np.testing.assert_allclose(m.actuator_ctrlrange[1], [np.radians(-2) - 10 / kp, 0 + 10 / kp], rtol=1e-6)
    assert not m.actuator_ctrllimited.any() and m.actuator_forcelimited.all()
    np.testing.assert_allclose(m.key_qpos[0], [0, 0, 0.42, 1, 0, 0, 0, 0.0, -0.6])
    np.testing.assert_allclose(m.key_ctrl[0], [0.0, -0.6])
    # the visual box is gone; the collision policy: the foot condim 6, the rest 1, nothing else collides
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) for g in range(m.ngeom)]
    assert names == ["terrain", "robot/base_collision", "robot/leg_collision", "robot/foot_collision"]
    assert list(m.geom_condim[1:]) == [1, 1, 6]
    # what the velocity task reads and the file lacks: the IMU at the base, its angular momentum, a site at the foot
    assert [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SENSOR, s) for s in range(m.nsensor)] == [
        "robot/imu_ang_vel", "robot/imu_lin_vel", "robot/root_angmom", "feet_ground_contact_foot_collision_found",
        "feet_ground_contact_foot_collision_force"]
    assert [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SITE, s) for s in range(m.nsite)] == [
        "robot/imu", "robot/foot_collision_site"]
    np.testing.assert_allclose(m.site_pos[1], [0, 0, -0.2])  # the foot geom's place in its body


@pytest.mark.parametrize("change, says", [
    ({"file": "/nowhere/robot.xml"}, "does not exist"),
    ({"root": "torso"}, "no body 'torso' to be the base; its bodies are ['base', 'leg', 'shin']"),
    ({"feet": ("toe",)}, "no foot geom(s) ['toe']"),
    ({"actuators": (Actuator("ankle", 5.0, 0.01, 1.0, 0.1),)}, "matches no joint"),
    ({"actuators": ()}, "no actuators"),
    ({"actuators": (Actuator("hip|knee", 5.0),)}, "give stiffness and damping, or an armature > 0"),
    ({"actuators": (Actuator("hip|knee", 5.0, stiffness=1.0, damping=0.1), Actuator("knee", 5.0, stiffness=1.0,
                                                                                      damping=0.1))},
     "matches two actuators"),
    ({"feet_are": "hoof"}, "feet_are='hoof'"),
])
def test_a_wrong_definition_is_one_line_naming_the_value(toy, change, says):
    with pytest.raises(ValueError) as e:
        build_scene(RobotFile(**{**toy.__dict__, **change}))
    assert says in str(e.value) and "\n" not in str(e.value)


def test_rough_ground_takes_an_empty_terrain_body_and_the_touch_sensors_a_task_reads(toy):
    m = build_scene(toy, floor=False, self_collision=True, touches=(("leg_touch", ("leg_.*",)),)).compile()
    assert m.ngeom == 3 and mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "terrain") == 1  # no plane
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_SENSOR, s) for s in range(m.nsensor)]
    assert names[5:] == ["self_collision_base_found", "self_collision_base_force", "leg_touch_leg_collision_found",
                         "leg_touch_leg_collision_force"]
    assert list(m.sensor_intprm[7:, 1]) == [0, 0]  # every contact of the group, not their net force
    with pytest.raises(ValueError, match=r"touches 'shin_touch': no geom of .* matches \['shin_.*'\]"):
        build_scene(toy, touches=(("shin_touch", ("shin_.*",)),))

