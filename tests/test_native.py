"""warpgym against native MuJoCo (the C library, loaded from the same MJCF): the same state gives the
same observation term by term, and the same actions move both alike for a few steps.

Tolerances: warpgym runs in float32 and native MuJoCo in float64. With iteration caps high enough
for both solvers to converge (the Ant's default of 4 is not: each then stops at a different
unconverged point) and the robot standing on the ground, the two agree to about 1e-5 over five
steps. The test allows 1e-3 per observation entry, which a real mismatch (a wrong gear, armature,
frame or quaternion order) exceeds by orders of magnitude.
"""

import numpy as np
import pytest
import torch

from warpgym.native.robots import NativeRobot, observation_slices, quat_rotate, quat_rotate_inv
from warpgym.sim.physics import Physics

TOLERANCE = 1e-3
# Zero-action steps from a reset until every robot stands on the ground, before any has fallen.
SETTLE = {"Ant": 60, "Humanoid": 15}
CONVERGED = {"solver_iterations": 50, "ls_iterations": 50}


def warpgym_state(sim) -> dict:
    return {k: getattr(sim, k).numpy().astype(np.float64) for k in ("root_pose", "root_vel", "dof_pos", "dof_vel")}


@pytest.mark.parametrize("task, integrator", [("Ant", "implicitfast"), ("Humanoid", "implicitfast"),
                                             ("Humanoid", "implicit")])
def test_native_mujoco_observes_and_steps_like_warpgym(task, integrator):
    from warpgym.envs import LocomotionVecEnv

    env = LocomotionVecEnv(task, num_envs=3, device="cpu", seed=0, physics={**CONVERGED, "integrator": integrator})
    assert int(env.sim.solver.mjw_model.opt.integrator) == {"implicitfast": 3, "implicit": 2}[integrator]
    env.reset(seed=11)
    zeros = torch.zeros(env.num_envs, env.num_actions)
    for _ in range(SETTLE[task]):
        _, _, terminated, truncated, _ = env.step(zeros)
        assert not (terminated | truncated).any()
    native = NativeRobot(env.task, copies=env.num_envs)
    assert native.model.opt.integrator == int(env.sim.solver.mjw_model.opt.integrator)  # both step alike
    assert native.dof_names == env.sim.dof_names
    state = warpgym_state(env.sim)
    native.set_state(**state)
    for key, value in native.state().items():
        np.testing.assert_allclose(value, state[key], atol=1e-6, err_msg=key)

    columns = observation_slices(env.task, env.num_actions, len(native.feet))
    gen = torch.Generator().manual_seed(4)
    touched = 0.0
    for step in range(5):
        actions = (torch.rand(env.num_envs, env.num_actions, generator=gen) * 2 - 1) * 0.3
        obs, *_ = env.step(actions)
        native.step(actions.numpy())
        theirs = native.observation(env.actions.numpy())
        for term, cols in columns.items():
            gap = np.abs(obs.numpy()[:, cols] - theirs[:, cols]).max()
            assert gap < TOLERANCE, f"step {step}: {term} differs by {gap:.2e}"
        touched = max(touched, np.abs(theirs[:, columns["feet"]]).max())
    assert touched > 0.05, "the feet never touched the ground: the contact terms were not compared"


def test_state_mapping_converts_frames():
    """A spinning, tilted root: MuJoCo's body-frame angular velocity and origin velocity are converted."""
    native = NativeRobot("Humanoid", copies=1)
    q = np.array([[0.2, -0.1, 0.3, 0.9]])
    q /= np.linalg.norm(q)
    w = np.array([[1.0, -2.0, 0.5]])
    pose = np.concatenate([[[0.1, 0.2, 1.5]], q], axis=1)
    vel = np.concatenate([[[0.3, 0.0, -0.2]], w], axis=1)
    dofs = np.zeros((1, len(native.dof_names)))
    native.set_state(pose, vel, dofs, dofs)
    d = native.data[0]
    np.testing.assert_allclose(d.qpos[3:7], [q[0, 3], *q[0, :3]])  # wxyz
    np.testing.assert_allclose(d.qvel[3:6], quat_rotate_inv(q, w)[0], atol=1e-12)  # body frame
    offset = quat_rotate(q, native.model.body_ipos[native.root_body][None])[0]
    assert np.linalg.norm(offset) > 0.01, "the Humanoid's torso COM is off its origin: the test needs that"
    np.testing.assert_allclose(d.qvel[:3] + np.cross(w[0], offset), vel[0, :3], atol=1e-12)
    back = native.state()
    np.testing.assert_allclose(back["root_vel"], vel, atol=1e-12)


def test_native_model_takes_the_physics_settings():
    native = NativeRobot("Ant", substeps=8, physics={"armature": 0.05, "contact_timeconst": 0.03,
                                                     "integrator": "euler", "solver_iterations": 20})
    m = native.model
    assert m.opt.timestep == pytest.approx(1 / 480) and m.opt.integrator == 0 and m.opt.iterations == 20
    np.testing.assert_allclose(m.dof_armature[native.dof_adr], 0.05)
    np.testing.assert_allclose(m.geom_solref[:, 0], 0.03)
    ant = native.task.physics  # the task's settings, with the four given ones changed
    assert native.physics == Physics(integrator="euler", solver_iterations=20, ls_iterations=ant.ls_iterations,
                                     armature=0.05, contact_timeconst=0.03, max_joint_speed=ant.max_joint_speed)
    np.testing.assert_allclose(native.torque_scale, 15.0)  # nv_ant.xml's gear, from MuJoCo's actuator table


def test_joint_speed_clamp_holds_in_both_simulators(ant_env):
    from warpgym.envs import LocomotionVecEnv

    def peak_speed(step, read, n):
        peak = 0.0
        for i in range(6):  # full torque, reversed every two steps: the joints swing through their range
            step(torch.full((n, 8), 1.0 if i // 2 % 2 == 0 else -1.0))
            peak = max(peak, float(np.abs(read()).max()))
        return peak

    env = LocomotionVecEnv("Ant", num_envs=2, device="cpu", seed=0, physics={"max_joint_speed": 2.0})
    native = NativeRobot(env.task, copies=2, physics={"max_joint_speed": 2.0})
    env.reset(seed=1)
    native.reset(np.random.default_rng(1))
    assert peak_speed(env.step, lambda: env.sim.dof_vel.numpy(), 2) <= 2.0 + 1e-5
    assert peak_speed(lambda a: native.step(a.numpy()), lambda: native.state()["dof_vel"], 2) <= 2.0 + 1e-9
    ant_env.reset(seed=1)
    assert peak_speed(ant_env.step, lambda: ant_env.sim.dof_vel.numpy(), ant_env.num_envs) > 4.0, \
        "without the clamp the same torques swing the joints faster: the clamp was not tested"


@pytest.mark.parametrize("bad, text", [({"integrator": "rk5"}, "integrator='rk5'"),
                                       ({"armature": -1.0}, "armature=-1.0"),
                                       ({"solver_iterations": 0}, "solver_iterations=0"),
                                       ({"stiffness": 3}, "unknown physics setting")])
def test_bad_physics_settings_are_refused(bad, text):
    with pytest.raises(ValueError, match=text):
        Physics.from_dict(bad)
