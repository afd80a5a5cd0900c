"""The velocity tasks with a robot of one's own (warpgym.tasks.legged.robot_task, definition.py, urdf.py): the parts a
definition derives against those mjlab's two tasks name by hand, the zoo's robots built from their URDF and MJCF
files and stepped by MuJoCo Warp as native MuJoCo steps them, a URDF's paths, limits and links, the TOML definition,
and each bad input refused in one line before anything trains."""

import dataclasses
import os

import numpy as np
import pytest

mujoco = pytest.importorskip("mujoco")

from warpgym.tasks.legged import LEGGED  # noqa: E402
from warpgym.tasks.legged.robot_file import Actuator, RobotFile, build_scene  # noqa: E402
from warpgym.tasks.legged.robot_task import PYTHON_ZOO, load_robot, robot_parts, stands, velocity_task, zoo  # noqa: E402

PARTS = ("root_body", "upright_body", "angvel_body", "com_body", "foot_geoms", "foot_sites", "foot_sensors")
TOUCHES = ("self_collision_sensor", "illegal_contact_sensors", "shank_sensors", "trunk_sensors")


def has_zoo_files() -> bool:
    import importlib.util

    return importlib.util.find_spec("pybullet_data") is not None


needs_zoo = pytest.mark.skipif(not has_zoo_files(), reason="the zoo's files: pip install 'warpgym[zoo]'")


@pytest.mark.parametrize("task", ["Go1VelocityFlat-v0", "G1VelocityFlat-v0", "Go1VelocityRough-v0",
                                  "G1VelocityRough-v0"])
def test_a_definition_derives_the_parts_mjlabs_tasks_name_by_hand(task):
    """What the terms read of the robot, named in mjlab's Go1 and G1 tasks field by field, is what their robots'
    definitions derive; the rough tasks' touches and self-collisions too (the flat Go1 reads none)."""
    spec = LEGGED[task]
    derived = robot_parts(spec.robot)
    names = PARTS + (TOUCHES if spec.terrain is not None or spec.self_collision_sensor else ())
    assert {n: derived[n] for n in names} == {n: getattr(spec, n) for n in names}


def test_the_generic_task_with_the_go1_is_mjlabs_go1_but_for_its_contact_room():
    """``VelocityFlat-v0`` with the Go1's definition: the Go1's pose stds (its posture), condim-6 feet's three
    friction events and every part of mjlab's Go1 task; only MuJoCo Warp's room, derived from what collides, is
    larger than mjlab's hand-set 32 contacts."""
    ours, mjlabs = velocity_task("go1"), LEGGED["Go1VelocityFlat-v0"]
    assert ours.rewards == mjlabs.rewards and ours.events == mjlabs.events
    assert all(getattr(ours, n) == getattr(mjlabs, n) for n in PARTS)
    assert ours.nconmax >= mjlabs.nconmax and ours.njmax >= mjlabs.njmax


def test_a_task_takes_another_robot_by_name_and_rederives_what_names_it():
    go1 = LEGGED["VelocityFlat-v0"].replace(robot="go1")
    assert go1.robot is load_robot("go1") and go1.foot_sites == LEGGED["Go1VelocityFlat-v0"].foot_sites
    g1 = LEGGED["VelocityFlat-v0"].replace(robot="g1", lin_vel_x=(-0.5, 0.5))
    assert g1.root_body == "robot/pelvis" and g1.upright_body == "robot/torso_link" and g1.lin_vel_x == (-0.5, 0.5)
    # the G1's definition's own changes: its torso's rates and self-collisions charged as mjlab charges them
    assert g1.rewards["self_collisions"].weight == -1.0 and g1.rewards["body_ang_vel"].weight == -0.05
    assert g1.rewards == LEGGED["G1VelocityFlat-v0"].rewards  # its posture: mjlab's stds joint by joint


@needs_zoo
@pytest.mark.parametrize("robot", sorted(set(zoo()) - set(PYTHON_ZOO)))
def test_each_zoo_robot_builds_on_both_grounds_and_stands(robot):
    """A zoo definition names a URDF or MJCF file of pybullet_data: its scene builds flat and rough (the touches of
    the rough ground from the definition) and its actuators hold its standing pose."""
    from warpgym.tasks.legged.model import compile_task_scene, resolve

    for rough in (False, True):
        task = velocity_task(robot, rough=rough)
        stands(task)
        m = compile_task_scene(task)[0].mjm
        idx = resolve(task, m)
        assert len(idx.foot_site) == len(task.robot.feet) and m.nu == len(idx.joint_names) >= 12
        assert bool(task.illegal_contact_sensors) == rough and np.isfinite(idx.action_scale).all()


@needs_zoo
@pytest.mark.parametrize("robot, tol", [("a1", 1e-5), ("aliengo", 1e-5), ("mini_cheetah", 1e-5), ("humanoid", 1e-5),
                                        ("laikago", 5e-3)])
def test_mujoco_warp_steps_the_zoo_robots_as_native_mujoco_does(robot, tol):
    """100 physics steps from the standing pose under random position targets, MuJoCo Warp (float32) against
    ``mj_step``: within 1e-5 in qpos for the robots of primitives and the Mini Cheetah's convex hulls; the Laikago's
    hulls, whose ten contacts MuJoCo Warp finds in float32, part by up to 1e-3."""
    import torch

    from warpgym.sim.mjw_sim import MjwSim
    from warpgym.tasks.legged.model import compile_task_scene

    task = velocity_task(robot)
    compiled = compile_task_scene(task)[0]
    m = compiled.mjm
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    sim = MjwSim(compiled, 1, "cpu", frame_skip=1, nconmax=task.nconmax, njmax=task.njmax)
    sim.set_state(torch.tensor(d.qpos[None], dtype=torch.float32), torch.tensor(d.qvel[None], dtype=torch.float32))
    rng = np.random.default_rng(0)
    worst, touched = 0.0, 0
    for _ in range(100):
        ctrl = m.key_ctrl[0] + rng.uniform(-0.3, 0.3, m.nu)
        d.ctrl[:] = ctrl
        sim.ctrl[0] = torch.tensor(ctrl, dtype=torch.float32)
        mujoco.mj_step(m, d)
        sim.simulate()
        worst = max(worst, float(np.abs(sim.to_torch(sim.d.qpos)[0].numpy() - d.qpos).max()))
        touched = max(touched, d.ncon)
    assert touched >= 2 and worst < tol, (worst, touched)


URDF = """<robot name="toy">
  <link name="base">
    <inertial><mass value="2"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="package://toy_description/meshes/missing_visual.dae"/></geometry></visual>
    <collision><geometry><mesh filename="package://toy_description/meshes/body.obj"/></geometry></collision>
  </link>
  <joint name="hip" type="revolute"><parent link="base"/><child link="leg"/><origin xyz="0 0 -0.05"/>
    <axis xyz="0 1 0"/><limit effort="12" lower="-1" upper="1" velocity="20"/></joint>
  <link name="leg">
    <inertial><origin xyz="0 0 -0.1"/><mass value="0.3"/><inertia ixx="1e-3" iyy="1e-3" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0 0 -0.1"/><geometry><cylinder radius="0.02" length="0.2"/></geometry></collision>
  </link>
  <joint name="toe_fixed" type="fixed"><parent link="leg"/><child link="toe"/><origin xyz="0 0 -0.2"/></joint>
  <link name="toe">
    <inertial><mass value="0.05"/><inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><geometry><sphere radius="0.02"/></geometry></collision>
  </link>
</robot>
"""
CUBE = "".join(f"v {x} {y} {z}\n" for x in (-0.1, 0.1) for y in (-0.05, 0.05) for z in (-0.03, 0.03)) + \
    "f 1 2 4 3\nf 5 7 8 6\nf 1 5 6 2\nf 3 4 8 7\nf 1 3 7 5\nf 2 6 8 4\n"


@pytest.fixture
def toy_urdf(tmp_path):
    pkg = tmp_path / "toy_description"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "meshes" / "body.obj").write_text(CUBE)
    (pkg / "urdf").mkdir()
    (pkg / "urdf" / "toy.urdf").write_text(URDF)
    return RobotFile(str(pkg / "urdf" / "toy.urdf"), root="base", feet=("toe_collision",), package_root=str(pkg),
                     actuators=(Actuator("hip", stiffness=10.0, damping=0.5),))


def test_a_urdf_gets_a_floating_base_its_links_its_package_paths_and_its_effort_limits(toy_urdf):
    m = build_scene(toy_urdf).compile()
    name = lambda kind, i: mujoco.mj_id2name(m, kind, i)  # noqa: E731
    assert m.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE and name(mujoco.mjtObj.mjOBJ_JOINT, 0) == "robot/floating_base"
    # the toe hangs by a fixed joint and stays a body of its own; the collisions are named by their links
    assert [name(mujoco.mjtObj.mjOBJ_BODY, b) for b in range(m.nbody)][-3:] == ["robot/base", "robot/leg", "robot/toe"]
    assert [name(mujoco.mjtObj.mjOBJ_GEOM, g) for g in range(m.ngeom)] == [
        "terrain", "robot/base_collision", "robot/leg_collision", "robot/toe_collision"]
    assert m.nmesh == 1 and m.geom_type[1] == mujoco.mjtGeom.mjGEOM_MESH  # the visual .dae was never read
    np.testing.assert_allclose(m.actuator_forcerange[0], [-12, 12])  # the URDF's effort
    # the toe rests 1 mm above the floor at the standing pose
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    mujoco.mj_kinematics(m, d)
    assert d.geom_xpos[3, 2] - 0.02 == pytest.approx(0.001, abs=1e-9)


def test_a_urdfs_paths_and_limits_refused_in_one_line(toy_urdf, tmp_path):
    cases = [
        (dataclasses.replace(toy_urdf, package_root=""), "is in ROS package 'toy_description': set package_root"),
        (dataclasses.replace(toy_urdf, package_root=str(tmp_path / "elsewhere")), "body.obj' is missing"),
        (dataclasses.replace(toy_urdf, root="leg"), "the base 'leg' hangs from 'base'"),
        (dataclasses.replace(toy_urdf, feet=("toe",)), "no foot geom(s) ['toe']"),
    ]
    for robot, says in cases:
        with pytest.raises(ValueError) as e:
            build_scene(robot)
        assert says in str(e.value) and "\n" not in str(e.value), str(e.value)
    unlimited = open(toy_urdf.file).read().replace('effort="12" ', "")
    path = tmp_path / "unlimited.urdf"
    path.write_text(unlimited)
    with pytest.raises(ValueError, match="has no effort limit in .*: give the actuator an effort_limit"):
        build_scene(dataclasses.replace(toy_urdf, file=str(path)))


@needs_zoo
def test_an_inertia_mujoco_rejects_names_the_option_that_fixes_it():
    """The Mini Cheetah's URDF breaks A + B >= C: without balance_inertia, one line naming the definition's key."""
    from warpgym.tasks.legged.model import compile_task_scene

    robot = dataclasses.replace(load_robot("mini_cheetah"), balance_inertia=False)
    with pytest.raises(ValueError) as e:
        compile_task_scene(velocity_task(robot))
    assert "set balance_inertia = true" in str(e.value) and "\n" not in str(e.value)


def test_a_robot_that_cannot_carry_its_weight_is_told_before_training(toy_urdf):
    with pytest.raises(ValueError, match="cannot stand at its pose with its gains: .* raise the actuators' stiffness"):
        stands(velocity_task(dataclasses.replace(toy_urdf, joint_pos={"hip": 0.6},
                                                 actuators=(Actuator("hip", stiffness=0.01, damping=0.01),))))


TOML = '''name = "toy"
file = "urdf/toy.urdf"
package_root = "."
root = "base"
feet = ["toe_collision"]

[[actuators]]
joints = "hip"
stiffness = 10.0
damping = 0.5
'''


def test_a_toml_definition_is_the_robot_file_its_keys_say(toy_urdf, tmp_path):
    from warpgym.tasks.legged.definition import load_definition

    folder = os.path.dirname(os.path.dirname(toy_urdf.file))
    path = os.path.join(folder, "toy.toml")
    with open(path, "w") as f:
        f.write(TOML)
    assert load_definition(path) == dataclasses.replace(toy_urdf, name="toy")
    for text, says in [
        ("mass = 3\n" + TOML, "no key(s) ['mass'] in a robot's definition"),
        (TOML.replace('root = "base"\n', ""), "a robot's definition needs ['root']"),
        (TOML + "[[actuators]]\njoint = 'x'\n", "actuators[1] has no key(s) ['joint']"),
        (TOML + "feet = [", "not valid TOML"),
        ('data_package = "no_such_package"\n' + TOML, "data_package='no_such_package' is not installed"),
    ]:
        with open(path, "w") as f:
            f.write(text)
        with pytest.raises(ValueError) as e:
            load_definition(path)
        assert says in str(e.value) and "\n" not in str(e.value), str(e.value)
    with pytest.raises(ValueError, match="is a robot file; the task needs its definition too"):
        load_robot(toy_urdf.file)
    with pytest.raises(ValueError, match=r"no zoo robot of that name \(go1, g1"):
        load_robot("spot")


def test_warpgym_train_checks_the_robot_before_anything_trains(toy_urdf, tmp_path):
    from warpgym.cli import train_args

    for argv, says in [(["--robot", "a1", "--task", "Ant"], "is not a legged velocity task"),
                       (["--robot", str(tmp_path / "none.toml")], "does not exist"),
                       (["--robot", "go1", "--resume", str(tmp_path)], "no config.json there")]:
        with pytest.raises(SystemExit):
            train_args.parse_args(argv)
    args = train_args.parse_args(["--robot", "go1", "--task", "VelocityRough-v0"])
    assert args.task == "VelocityRough-v0" and args.robot == "go1"
    args = train_args.parse_args(["--robot", "g1"])
    assert args.task == "VelocityFlat-v0"


def l_block_obj() -> str:
    """An L of 0.3 m arms, 0.1 m wide and 0.1 m tall, as one closed, non-convex OBJ mesh: its hull fills the notch
    between the arms."""
    outline = [(0, 0), (0.3, 0), (0.3, 0.1), (0.1, 0.1), (0.1, 0.3), (0, 0.3)]
    n = len(outline)
    verts = [(x, y, 0.0) for x, y in outline] + [(x, y, 0.1) for x, y in outline]
    faces = []
    for a, b, c in ((0, 1, 2), (0, 2, 3), (0, 3, 4), (0, 4, 5)):
        faces += [(a, c, b), (a + n, b + n, c + n)]
    for i in range(n):
        j = (i + 1) % n
        faces += [(i, j, j + n), (i, j + n, i + n)]
    return "".join(f"v {x} {y} {z}\n" for x, y, z in verts) + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in faces)


def test_convex_decomposition_splits_a_non_convex_mesh_that_its_hull_would_fill(tmp_path, monkeypatch):
    """An L-shaped body collides as its hull by default; decomposed, as CoACD's convex parts: a ball dropped over
    the notch between its arms rests on the hull's top, but on the floor once the L is split; the parts come from
    the cache the second time (CoACD not called)."""
    pytest.importorskip("coacd")
    from warpgym.tasks.legged import convex

    monkeypatch.setenv("WARPGYM_CACHE", str(tmp_path / "cache"))
    (tmp_path / "l.obj").write_text(l_block_obj())
    xml = f"""<mujoco><compiler meshdir="{tmp_path}"/><asset><mesh name="l" file="l.obj"/></asset><worldbody>
      <geom name="floor" type="plane" size="2 2 0.1"/>
      <body name="block"><geom name="l_collision" type="mesh" mesh="l" mass="1"/></body>
      <body name="ball" pos="0.17 0.17 0.3"><freejoint/><geom type="sphere" size="0.03" mass="0.1"/></body>
    </worldbody></mujoco>"""

    def rest_height(split: bool) -> float:
        spec = mujoco.MjSpec.from_string(xml)
        if split:
            split = convex.decompose(spec, lambda s: s.compile())
            assert list(split) == ["l_collision"] and split["l_collision"] >= 2
        m = spec.compile()
        d = mujoco.MjData(m)
        for _ in range(1000):
            mujoco.mj_step(m, d)
        return float(d.qpos[2])

    assert rest_height(False) == pytest.approx(0.1 + 0.03, abs=5e-3)  # on the hull, over the notch
    assert rest_height(True) == pytest.approx(0.03, abs=5e-3)  # in the notch, on the floor
    assert len(os.listdir(tmp_path / "cache" / "convex")) == 1

    import coacd

    monkeypatch.setattr(coacd, "run_coacd", lambda *a, **k: pytest.fail("the cache was not read"))
    assert rest_height(True) == pytest.approx(0.03, abs=5e-3)


def test_a_robot_definition_turns_decomposition_on(tmp_path, monkeypatch, toy_urdf):
    """``convex_decomposition`` in a definition: the robot's non-convex collision mesh becomes parts that collide as
    it did (its contact settings), the original kept for its mass alone; a convex one (the toy's box) stays whole."""
    pytest.importorskip("coacd")
    monkeypatch.setenv("WARPGYM_CACHE", str(tmp_path / "cache"))
    box = build_scene(dataclasses.replace(toy_urdf, convex_decomposition=True)).compile()
    assert box.nmesh == 1
    # a file of its own: MuJoCo caches a mesh by its file's name
    with open(os.path.join(toy_urdf.package_root, "meshes", "l.obj"), "w") as f:
        f.write(l_block_obj())
    urdf = tmp_path / "l.urdf"
    urdf.write_text(open(toy_urdf.file).read().replace("meshes/body.obj", "meshes/l.obj"))
    l_robot = dataclasses.replace(toy_urdf, file=str(urdf))
    m = build_scene(dataclasses.replace(l_robot, convex_decomposition=True)).compile()
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g) for g in range(m.ngeom)]
    parts = [g for g, n in enumerate(names) if n.startswith("robot/base_collision_part")]
    whole = names.index("robot/base_collision")
    assert len(parts) >= 2 and m.geom_contype[whole] == m.geom_conaffinity[whole] == 0
    assert all((m.geom_contype[p], m.geom_conaffinity[p]) == (2, 1) for p in parts)  # no self-collisions
    plain = build_scene(l_robot).compile()
    np.testing.assert_allclose(m.body_mass, plain.body_mass)
    np.testing.assert_allclose(m.body_inertia, plain.body_inertia)
