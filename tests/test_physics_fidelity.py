"""Each task's physics holds at a finer step for the gaits PPO learns on it.

Ant: two policies trained on an H100 (tests/data, each checkpoint's "note"), replayed closed loop in
warpgym on the CPU at the task's step and at 4x the substeps:
- the flying policy was fitted to an exploitable step (a soft contact). With the defaults of
  2026-11-22 (nv_ant.xml's armature 0.01) it flies at the training step, torso about 1.3 m up, and
  loses half its speed at the finer step: the physics pays out the integration error. With the
  task's physics it runs at the same speed at both steps;
- the 10-minute policy of today's default (4 substeps of 4 iterations, armature 0.1) keeps its speed.

Humanoid: policies trained on an H100 at 4096 envs. The 200-second policy of the 2-substep default (until
2026-11-24) runs faster at its own step than at a 4x finer one; the 10-minute policy of the 3-substep
default that followed (seed 0) kept its speed, its seed 1 did not, nor did seed 1 at 5 substeps
(tests/data/humanoid_5x4_seed1_policy.pt, a sprint that draws a quarter of its speed from the step).
Today's default (3 substeps, 25 rad/s motors, armature 0.1) holds both seeds' 10-minute policies. The
default tests pick the committed policies trained with the task's physics, so they fail when a default
changes without them.

docs/history.md ("Physics settings: the investigation") has the same replays at full length on the GPU and in native
MuJoCo.
"""

import os

import numpy as np
import pytest
import torch

DATA = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data")
STEPS, ROBOTS = 600, 8
OLD_ANT_PHYSICS = {"armature": None, "solver_iterations": 4, "ls_iterations": 4}  # the defaults until 2026-11-23
OLD_HUMANOID_PHYSICS = {"armature": None, "motor_speed": None, "solver_iterations": 8,
                        "ls_iterations": 8}  # at 2 substeps, until 2026-11-24 morning
HUMANOID_POLICIES = ("humanoid_2x8_policy.pt", "humanoid_3x8_policy.pt", "humanoid_motor_seed0_policy.pt",
                     "humanoid_motor_seed1_policy.pt")
ANT_POLICIES = ("ant_4x4_policy.pt",)  # ant_armature_policy.pt: 3 substeps, the default until 2026-11-24


def replay(name: str, substeps: int, physics=None, task: str = "Ant") -> dict:
    """Mean forward speed and torso height of ROBOTS robots over STEPS steps of the policy ``name``, on
    ``physics`` (a Physics or a dict of its fields; None: the task's)."""
    from agents.checkpoint import load, policy_from_checkpoint
    from warpgym.envs import LocomotionVecEnv

    ckpt = load(os.path.join(DATA, name), torch.device("cpu"))
    overrides = {"physics": physics} if physics is not None else {}  # else the task's, not the checkpoint's
    env = LocomotionVecEnv(task, num_envs=ROBOTS, device="cpu", seed=3, substeps=substeps,
                           max_episode_steps=STEPS, **overrides)
    policy, normalize = policy_from_checkpoint(ckpt, env.num_obs, env.num_actions, torch.device("cpu"))
    obs, _ = env.reset(seed=3)
    speed, height, up = np.zeros(ROBOTS), np.zeros(ROBOTS), np.ones(ROBOTS, bool)
    alive = np.zeros(ROBOTS)
    with torch.no_grad():
        for _ in range(STEPS):
            obs, _, terminated, truncated, info = env.step(policy.act_deterministic(normalize(obs)))
            done = (terminated | truncated).numpy()
            now = torch.where(terminated | truncated, info["episode"]["s"], info["episode_so_far"]["s"]).numpy()
            speed = np.where(up, now, speed)
            height += np.where(up & ~done, env.sim.root_pose[:, 2].numpy(), 0.0)
            alive += up & ~done
            up &= ~done
    return {"speed": float(speed.mean()), "height": float(height.sum() / max(alive.sum(), 1)),
            "physics": env.task.physics}


def same_speed(a: float, b: float) -> bool:
    """Issue 22's agreement: within 10 % or 0.5 m/s, whichever is larger."""
    return abs(a - b) <= max(0.1 * max(abs(a), abs(b)), 0.5)


@pytest.mark.slow
def test_an_exploiting_gait_flies_on_the_old_physics_and_not_on_the_tasks():
    from warpgym.tasks.robots import get_task

    coarse, fine = replay("ant_flying_policy.pt", 3, OLD_ANT_PHYSICS), replay("ant_flying_policy.pt", 12, OLD_ANT_PHYSICS)
    # the mechanism, on the old physics: speed and height come from the step, not the robot
    assert coarse["height"] > 1.2 and coarse["speed"] > 1.5 * fine["speed"], (coarse, fine)
    steps = get_task("Ant").substeps
    coarse, fine = replay("ant_flying_policy.pt", steps), replay("ant_flying_policy.pt", 4 * steps)
    assert coarse["physics"].armature == 0.1
    assert same_speed(coarse["speed"], fine["speed"]) and coarse["height"] < 1.0, (coarse, fine)


def trained_with(name: str):
    """The substeps and physics a committed policy was trained with (its checkpoint's config); a
    setting added since then has its default."""
    from agents.checkpoint import load
    from warpgym.tasks.robots import trained_task

    task = trained_task(load(os.path.join(DATA, name), torch.device("cpu"))["config"]["env_args"])
    return task.substeps, task.physics


@pytest.mark.slow
def test_the_humanoids_old_step_pays_out_speed_that_a_finer_step_does_not():
    coarse = replay("humanoid_2x8_policy.pt", 2, OLD_HUMANOID_PHYSICS, task="Humanoid")
    fine = replay("humanoid_2x8_policy.pt", 8, OLD_HUMANOID_PHYSICS, task="Humanoid")
    assert coarse["speed"] > 5.0, coarse
    assert fine["speed"] < 0.9 * coarse["speed"], (coarse, fine)  # 0.84 here, 0.81 on the GPU and in native MuJoCo


@pytest.mark.slow
@pytest.mark.parametrize("task_name, policies", [("Ant", ANT_POLICIES), ("Humanoid", HUMANOID_POLICIES)])
def test_a_gait_trained_on_the_default_physics_keeps_its_speed_at_a_finer_step(task_name, policies):
    from warpgym.tasks.robots import get_task

    task = get_task(task_name)
    trained_on_default = [n for n in policies if trained_with(n) == (task.substeps, task.physics)]
    assert trained_on_default, (
        f"no committed policy was trained with the {task_name}'s default ({task.substeps} substeps, {task.physics}): "
        "train one with benchmarks/physics/fidelity.py and commit it to tests/data")
    for name in trained_on_default:
        coarse = replay(name, task.substeps, task=task_name)
        fine = replay(name, 4 * task.substeps, task=task_name)
        assert coarse["speed"] > 5.0, (name, coarse)  # a real gait, not a robot standing still
        assert fine["speed"] >= 0.9 * coarse["speed"], (name, coarse, fine)


def test_a_policy_recorded_before_a_physics_setting_existed_replays_without_it():
    """humanoid_5x4_seed1_policy.pt was saved before Physics had motor_speed: merged onto today's Humanoid
    default it would replay on 25 rad/s motors it never saw; recorded() gives it the
    setting's own default, off, as play, sim2sim, step_sensitivity and --resume do; trained_task() is
    that physics on the task, with the checkpoint's substeps."""
    from agents.checkpoint import load
    from warpgym.sim.physics import recorded
    from warpgym.tasks.robots import get_task, trained_task

    env_args = load(os.path.join(DATA, "humanoid_5x4_seed1_policy.pt"), torch.device("cpu"))["config"]["env_args"]
    saved = env_args["physics"]
    assert "motor_speed" not in saved
    humanoid = get_task("Humanoid")
    assert humanoid.replace(physics=saved).physics.motor_speed == humanoid.physics.motor_speed == 25.0
    replayed = humanoid.replace(physics=recorded(saved)).physics
    assert replayed.motor_speed is None and replayed.armature is None and replayed.solver_iterations == 4
    assert recorded(None) == recorded({}) == {}
    task = trained_task(env_args)
    assert task.physics == replayed and task.substeps == 5 != humanoid.substeps
    assert trained_task({"task": "Ant"}) == get_task("Ant")  # nothing recorded: the task as it stands


def test_step_sensitivity_names_a_bad_setting():
    from benchmarks.physics.step_sensitivity import parse_setting

    assert parse_setting("substeps=10,damping[hip_z|ankle]=0.8") == {
        "label": "substeps=10,damping[hip_z|ankle]=0.8", "substeps": 10, "damping": [(("hip_z", "ankle"), 0.8)]}
    assert parse_setting("finer=4,integrator=implicit") == {"label": "finer=4,integrator=implicit", "finer": 4,
                                                            "integrator": "implicit"}
    for bad in ("stiffness=2", "damping=-1", "substeps=ten", "integrator=verlet"):
        with pytest.raises(ValueError, match="setting"):
            parse_setting(bad)


@pytest.mark.slow
def test_the_seed1_humanoid_gait_leans_on_joint_damping_and_no_constraint_pays_energy_in():
    """docs/tasks.md: the 5x4 seed-1 policy runs at its own step and falls with 30 % more damping on the
    abdomen and hip flexion joints; the motors put energy in, contacts and joint limits take it out."""
    from benchmarks.physics.step_sensitivity import parse_setting, replay as native_replay
    from agents.checkpoint import load
    from warpgym.tasks.robots import trained_task

    ckpt = load(os.path.join(DATA, "humanoid_5x4_seed1_policy.pt"), torch.device("cpu"))
    task = trained_task(ckpt["config"]["env_args"])
    own = native_replay(ckpt, task, {"label": "own"}, task.substeps, 2, 300, 7)
    damped = native_replay(ckpt, task, parse_setting("damping[abdomen|hip_x|hip_y]=1.3"), task.substeps, 2, 300, 7)
    assert own["falls"] == 0 and own["forward_speed"] > 5.0, own
    assert damped["falls"] == 2, damped
    power = own["power_w"]
    assert power["motors"] > 1000 and power["damping"] < 0 and power["contacts"] < 0 and power["limits"] <= 0, power


def test_the_humanoids_step_pays_its_seed1_gait_energy_and_the_ants_pays_none():
    """docs/tasks.md: the integrator column of step_sensitivity.py, the mechanical energy gained beyond
    the work of every force. The 5x4 seed-1 sprint takes energy from implicitfast's explicit treatment of
    the velocity-product forces at its own step, a quarter as much at 4x finer; the Ant's default gait
    takes none, which also checks the bookkeeping (a missed force would show up there)."""
    from benchmarks.physics.step_sensitivity import parse_setting, replay as native_replay
    from agents.checkpoint import load
    from warpgym.tasks.robots import trained_task

    def power(name, setting):
        ckpt = load(os.path.join(DATA, name), torch.device("cpu"))
        task = trained_task(ckpt["config"]["env_args"])
        substeps = task.substeps
        setting = parse_setting(setting) if setting else {"label": "own"}
        return native_replay(ckpt, task, setting, substeps, 2, 300, 7)["power_w"]

    own, finer = power("humanoid_5x4_seed1_policy.pt", None), power("humanoid_5x4_seed1_policy.pt", "finer=4")
    assert own["integrator"] > 0.05 * own["motors"], own
    assert 0 <= finer["integrator"] < 0.3 * own["integrator"], (own, finer)
    ant = power("ant_4x4_policy.pt", None)
    assert abs(ant["integrator"]) < 0.01 * ant["motors"], ant


def test_matched_damping_is_the_identity_at_its_own_step_and_lighter_at_a_finer_one():
    from benchmarks.physics.step_sensitivity import match_damping
    from warpgym.native.robots import NativeRobot

    same, finer = NativeRobot("Humanoid", substeps=5), NativeRobot("Humanoid", substeps=10)
    before = finer.model.dof_damping[finer.dof_adr].copy()
    match_damping(same, 5)
    match_damping(finer, 5)
    np.testing.assert_allclose(same.model.dof_damping[same.dof_adr], before, rtol=1e-9)
    after = finer.model.dof_damping[finer.dof_adr]
    # implicit Euler damps less per second at a coarser step: matching it takes damping away, most
    # where a joint is light (hip rotation, ankles), least where it is heavy or barely damped (knee)
    assert np.all(after < before) and np.all(after > 0.8 * before), after / before


def test_exact_damping_is_the_same_in_both_simulators_and_fades_as_the_step_shrinks():
    """Physics(exact_damping=True) scales each hinge's damping by (e^x - 1) / x, x = h d / I: warpgym
    (from its solver's model) and native MuJoCo (from the MJCF) scale alike, and the scale tends to 1
    at a finer step."""
    from warpgym.native.robots import NativeRobot
    from warpgym.sim import Sim
    from warpgym.tasks.robots import get_task

    task = get_task("Humanoid")
    mjcf = task.physics.replace(motor_speed=None, armature=None)  # the MJCF's damping and rotors alone
    physics = mjcf.replace(exact_damping=True)
    sim = Sim("humanoid", num_envs=2, device="cpu", substeps=task.substeps, physics=physics)
    coarse = NativeRobot(task, substeps=task.substeps, physics=physics)
    fine = NativeRobot(task, substeps=4 * task.substeps, physics=physics)
    plain = NativeRobot(task, substeps=task.substeps, physics=mjcf)
    d0 = plain.model.dof_damping[plain.dof_adr]
    damped = d0 > 0
    coarse_scale = coarse.model.dof_damping[coarse.dof_adr][damped] / d0[damped]
    fine_scale = fine.model.dof_damping[fine.dof_adr][damped] / d0[damped]
    np.testing.assert_allclose(sim.solver.mjw_model.dof_damping.numpy()[1, 6:], coarse.model.dof_damping[coarse.dof_adr],
                               rtol=1e-5)
    assert np.all(coarse_scale > 1.0) and coarse_scale.max() > 1.5, coarse_scale  # the hip rotation: about 1.8
    assert np.all(fine_scale > 1.0) and np.all(fine_scale - 1 < 0.3 * (coarse_scale - 1)), (coarse_scale, fine_scale)


def test_motor_back_emf_is_joint_damping_of_gear_over_no_load_speed_in_both_simulators():
    """Physics(motor_speed=w0) adds gear / w0 to the damping of every motor's joint (a DC motor at the
    full command stalls at w0), in warpgym and native MuJoCo alike, before exact_damping scales it."""
    from warpgym.native.robots import NativeRobot
    from warpgym.sim import Sim
    from warpgym.sim.physics import exact_damping_scale
    import mujoco

    from warpgym.tasks.robots import get_task

    task = get_task("Humanoid")
    mjcf = task.physics.replace(motor_speed=None, armature=None)
    motors = mjcf.replace(motor_speed=25.0)
    plain = NativeRobot(task, substeps=task.substeps, physics=mjcf)
    native = NativeRobot(task, substeps=task.substeps, physics=motors)
    d0 = plain.model.dof_damping[plain.dof_adr]
    added = native.model.dof_damping[native.dof_adr] - d0
    np.testing.assert_allclose(added, plain.torque_scale / 25.0, rtol=1e-12)  # power_scale is 1
    assert added.max() == pytest.approx(135.0 / 25.0)  # the hip flexion's motor: gear 135
    sim = Sim("humanoid", num_envs=2, device="cpu", substeps=task.substeps, physics=motors.replace(exact_damping=True))
    both = NativeRobot(task, substeps=task.substeps, physics=motors.replace(exact_damping=True))
    _, scale = exact_damping_scale(mujoco, native.model, native.model.opt.timestep)
    np.testing.assert_allclose(both.model.dof_damping[both.dof_adr], (d0 + added) * scale, rtol=1e-9)
    np.testing.assert_allclose(sim.solver.mjw_model.dof_damping.numpy()[1, 6:], both.model.dof_damping[both.dof_adr],
                               rtol=1e-5)
