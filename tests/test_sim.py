"""warpgym.Sim and its Isaac-like Tensor API on Warp's CPU backend."""

import math

import pytest
import torch

from warpgym import Sim

G = 9.81


def put(sim, z=0.55, quat=(0.0, 0.0, 0.0, 1.0), dof_vel=0.0):
    """Every env: root at height z with orientation quat, at rest; joints at their defaults."""
    n, k = sim.num_envs, sim.num_dofs
    ids = torch.arange(n, dtype=torch.int32)
    root = torch.zeros(n, 13)
    root[:, 2] = z
    root[:, 3:7] = torch.tensor(quat)
    sim.set_actor_root_state_tensor_indexed(root, ids)
    dofs = torch.zeros(n * k, 2)
    dofs[:, 0] = torch.as_tensor(sim.default_dof_pos_np).repeat(n)
    dofs[:, 1] = dof_vel
    sim.set_dof_state_tensor_indexed(dofs, ids)
    sim.set_dof_actuation_force_tensor(torch.zeros(n, k))


def test_tensor_shapes(ant_sim):
    n, k, b = ant_sim.num_envs, ant_sim.num_dofs, ant_sim.bodies_per_env
    assert (k, b) == (8, 9)
    assert ant_sim.acquire_actor_root_state_tensor().shape == (n, 13)
    assert ant_sim.acquire_dof_state_tensor().shape == (n * k, 2)
    assert ant_sim.acquire_rigid_body_state_tensor().shape == (n * b, 13)
    assert ant_sim.acquire_net_contact_force_tensor().shape == (n * b, 3)
    assert ant_sim.acquire_dof_force_tensor().shape == (n * k,)
    assert ant_sim.acquire_force_sensor_tensor().shape == (n * 4, 6)
    assert ant_sim.dof_pos.shape == ant_sim.dof_vel.shape == (n, k)
    assert ant_sim.root_pose.shape == (n, 7) and ant_sim.root_vel.shape == (n, 6)
    assert ant_sim.body_q.shape == (n, b, 7) and ant_sim.body_qd.shape == (n, b, 6)


def test_humanoid_has_21_dofs_and_gears_from_its_mjcf():
    sim = Sim("humanoid", num_envs=1, device="cpu")
    assert sim.num_dofs == 21
    assert sim.dof_names[:3] == ["abdomen_z", "abdomen_y", "abdomen_x"]
    gears = dict(zip(sim.dof_names, sim.motor_gear_np.tolist()))
    assert gears["right_hip_y"] == 135.0 and gears["left_ankle_x"] == 22.5


def test_root_state_quaternion_is_xyzw_and_agrees_with_body_transforms(ant_sim):
    s, c = math.sin(math.pi / 4), math.cos(math.pi / 4)
    put(ant_sim, z=0.8, quat=(0.0, 0.0, s, c))  # 90 degrees about +z
    ant_sim.step()
    root = ant_sim.acquire_actor_root_state_tensor()
    bodies = ant_sim.acquire_rigid_body_state_tensor().view(ant_sim.num_envs, -1, 13)
    torso, leg = 0, ant_sim.body_names.index("front_left_leg")
    torch.testing.assert_close(bodies[:, torso, :7], root[:, :7])
    assert torch.allclose(root[:, 3:7], torch.tensor([0.0, 0.0, s, c]), atol=1e-3)
    # the front-left hip sits at (0.2, 0.2, 0) in the torso frame; turned 90 degrees it is at (-0.2, 0.2)
    offset = bodies[:, leg, :3] - root[:, :3]
    assert torch.allclose(offset[:, :2], torch.tensor([-0.2, 0.2]), atol=1e-2)


def test_dof_state_matches_live_views(ant_sim):
    put(ant_sim)
    ant_sim.set_dof_actuation_force_tensor(torch.linspace(-3, 3, ant_sim.num_envs * ant_sim.num_dofs))
    for _ in range(5):
        ant_sim.step()
    state = ant_sim.acquire_dof_state_tensor()
    assert state[:, 1].abs().max() > 0.1
    torch.testing.assert_close(state[:, 0], ant_sim.dof_pos.reshape(-1))
    torch.testing.assert_close(state[:, 1], ant_sim.dof_vel.reshape(-1))


def test_views_are_zero_copy_stable_and_writable(ant_sim):
    put(ant_sim)
    pos, vel, root = ant_sim.dof_pos, ant_sim.dof_vel, ant_sim.root_pose
    ptrs = (pos.data_ptr(), vel.data_ptr(), root.data_ptr())
    before = pos.clone()
    vel[1, 0] = 4.0  # spin env 1's first hip through the view
    root[2, 2] = 2.0  # lift env 2 through the view
    ant_sim.step()
    assert (ant_sim.dof_pos.data_ptr(), ant_sim.dof_vel.data_ptr(), ant_sim.root_pose.data_ptr()) == ptrs
    assert pos[1, 0] - before[1, 0] > 0.02  # the write was seen by the step
    assert abs(pos[0, 0] - before[0, 0]) < 0.01
    assert root[2, 2] > 1.9 and root[0, 2] < 0.6


def test_indexed_setters_change_only_selected_envs(ant_sim):
    put(ant_sim)
    root = ant_sim.acquire_actor_root_state_tensor().clone()
    dofs = ant_sim.acquire_dof_state_tensor().clone()
    new_root = root.clone()
    new_root[:, 0] += 5.0
    new_dofs = dofs.clone()
    new_dofs[:, 1] = 0.7
    ids = torch.tensor([1], dtype=torch.int64)
    ant_sim.set_actor_root_state_tensor_indexed(new_root, ids)
    ant_sim.set_dof_state_tensor_indexed(new_dofs, ids)
    ant_sim.refresh_actor_root_state_tensor()
    ant_sim.refresh_dof_state_tensor()
    after_root = ant_sim.acquire_actor_root_state_tensor()
    after_dofs = ant_sim.acquire_dof_state_tensor().view(ant_sim.num_envs, -1, 2)
    assert torch.equal(after_root[1], new_root[1])
    assert torch.equal(after_root[[0, 2]], root[[0, 2]])
    assert torch.all(after_dofs[1, :, 1] == 0.7)
    assert torch.equal(after_dofs[[0, 2]], dofs.view(ant_sim.num_envs, -1, 2)[[0, 2]])


def test_dropped_ant_falls_and_rests_on_its_feet(ant_sim):
    put(ant_sim, z=1.0)
    heights = []
    for _ in range(150):  # 2.5 s
        ant_sim.step()
        heights.append(ant_sim.root_pose[0, 2].item())
    assert min(heights[:20]) < 1.0 and heights[-1] < 0.6  # it fell
    assert abs(heights[-1] - heights[-10]) < 1e-3  # and came to rest
    assert ant_sim.root_vel.abs().max() < 0.05
    contact = ant_sim.acquire_net_contact_force_tensor().view(ant_sim.num_envs, -1, 3)
    feet = ant_sim.foot_bodies.numpy().tolist()
    weight = float(ant_sim.model.body_mass.numpy()[: ant_sim.bodies_per_env].sum()) * G
    assert torch.all(contact[:, feet, 2] > 0.05 * weight)  # every foot carries load
    torch.testing.assert_close(contact[:, feet, 2].sum(1), torch.full((ant_sim.num_envs,), weight), rtol=0.03,
                               atol=0.0)
    others = [i for i in range(ant_sim.bodies_per_env) if i not in feet]
    assert contact[:, others].abs().max() < 1e-3 * weight
    sensors = ant_sim.acquire_force_sensor_tensor().view(ant_sim.num_envs, 4, 6)
    torch.testing.assert_close(sensors[:, :, :3], contact[:, feet])


def test_joint_torque_turns_the_joint_its_way(ant_sim):
    put(ant_sim, z=0.8)
    k = ant_sim.num_dofs
    forces = torch.zeros(ant_sim.num_envs, k)
    forces[0, 0], forces[1, 0] = 2.0, -2.0  # hip_1: +, -, and none in env 2
    ant_sim.set_dof_actuation_force_tensor(forces)
    for _ in range(6):
        ant_sim.step()
    hip = ant_sim.dof_pos[:, 0]
    assert hip[0] > hip[2] + 0.05 and hip[1] < hip[2] - 0.05
    assert ant_sim.acquire_dof_force_tensor().view(-1, k)[0, 0] > 1.0  # the applied torque is reported


def test_full_constraint_buffers_are_counted_per_world_and_substep():
    """An Ant standing on its four feet needs about 20 constraint rows; with room for 8 every world
    loses constraints in every substep, and the Sim counts it instead of printing."""
    from warpgym import Sim

    small = Sim("ant", num_envs=2, device="cpu", njmax=8)
    for _ in range(20):
        small.step()
    load = small.solver_load()
    assert load["njmax"] == 8 and load["peak_constraints_per_world"] > 8
    assert small.solver_overflows.numpy().tolist() == [small.substeps] * 2
    roomy = Sim("ant", num_envs=2, device="cpu")  # the default: room for the worst case on a plane
    for _ in range(20):
        roomy.step()
    load = roomy.solver_load()
    assert 8 < load["peak_constraints_per_world"] <= load["njmax"] == 128
    assert roomy.solver_overflows.numpy().tolist() == [0, 0]


def test_worlds_evolve_independently(ant_sim):
    put(ant_sim, z=0.7)
    gen = torch.Generator().manual_seed(3)
    for _ in range(20):
        a = torch.rand(ant_sim.num_dofs, generator=gen) * 6 - 3
        b = torch.rand(ant_sim.num_dofs, generator=gen) * 6 - 3
        ant_sim.set_dof_actuation_force_tensor(torch.stack([a, a, b]))
        ant_sim.step()
    q = ant_sim.acquire_dof_state_tensor().view(ant_sim.num_envs, -1, 2)
    torch.testing.assert_close(q[0], q[1], atol=1e-5, rtol=0)  # same actions, same states
    assert (q[0] - q[2]).abs().max() > 0.05  # different actions, different states


@pytest.mark.parametrize(
    "kwargs, error, words",
    [
        (dict(robot="spider"), ValueError, ["spider", "ant", "humanoid"]),
        (dict(num_envs=0), ValueError, ["num_envs=0"]),
        (dict(num_envs=2.5), ValueError, ["num_envs=2.5"]),
        (dict(device="cuda:7"), ValueError, ["cuda:7", "device='cpu'"]),
        (dict(device="gpu"), ValueError, ["'gpu'", "cuda:N"]),
        (dict(substeps=0), ValueError, ["substeps=0"]),
        (dict(dt=-0.01), ValueError, ["dt=-0.01"]),
    ],
)
def test_bad_construction_arguments_say_what_to_do(kwargs, error, words):
    args = dict(robot="ant", num_envs=1, device="cpu") | kwargs
    with pytest.raises(error) as info:
        Sim(**args)
    for w in words:
        assert w in str(info.value)


def test_bad_tensors_and_indices_are_refused(ant_sim):
    n, k = ant_sim.num_envs, ant_sim.num_dofs
    with pytest.raises(ValueError, match=r"shape \(5,\)"):
        ant_sim.set_dof_actuation_force_tensor(torch.zeros(5))
    with pytest.raises(TypeError, match="float64"):
        ant_sim.set_dof_actuation_force_tensor(torch.zeros(n, k, dtype=torch.float64))
    with pytest.raises(ValueError, match="meta"):
        ant_sim.set_dof_actuation_force_tensor(torch.zeros(n, k, device="meta"))
    with pytest.raises(IndexError, match=r"index 3, outside \[0, 2\]"):
        ant_sim.set_actor_root_state_tensor_indexed(torch.zeros(n, 13), torch.tensor([0, 3]))
    with pytest.raises(IndexError, match="index -1"):
        ant_sim.set_dof_state_tensor_indexed(torch.zeros(n * k, 2), torch.tensor([-1]))
    with pytest.raises(TypeError, match="int32 or int64"):
        ant_sim.set_dof_state_tensor_indexed(torch.zeros(n * k, 2), torch.tensor([0.0]))
    with pytest.raises(ValueError, match=r"expected \(3, 13\)"):
        ant_sim.set_actor_root_state_tensor_indexed(torch.zeros(13), torch.tensor([0]))


def test_too_many_envs_for_the_gpu_is_refused_before_allocating(monkeypatch):
    from warpgym.sim.robots import robot_spec

    sim = Sim.__new__(Sim)  # only the check, on a pretend GPU with 1 GiB free
    sim.spec, sim.num_envs, sim.device, sim.torch_device = robot_spec("humanoid"), 100_000, "cuda:0", None
    monkeypatch.setattr(torch.cuda, "mem_get_info", lambda device=None: (2**30, 80 * 2**30))
    with pytest.raises(MemoryError, match=r"num_envs=100000 .* 1.0 GiB free: pass num_envs <= 8378"):
        sim._check_memory()
    sim.num_envs = 4000
    sim._check_memory()


def test_one_conversion_per_step_moves_the_robot_as_newtons_step_does():
    """Sim.simulate converts Newton's state to MuJoCo's and back once per control step; Newton's
    public step converts every substep. From the same state with the same torques, both give the same
    joint state, body poses and contact wrenches, apart from float32 round trips: within 1e-5 of
    each value's scale after one step and 1e-4 after 30 steps of a robot kicking the ground."""
    sims = [Sim("ant", num_envs=3, device="cpu", substeps=3) for _ in range(2)]
    # the pinned Newton has the private phases (warpgym/sim/newton_internals.py): a Newton that moved
    # them fails here, not by silently falling back to the slower public step
    assert sims[0].convert_once_per_step, "SolverMuJoCo lacks the phases newton_internals.mujoco_substep calls"
    sims[1].convert_once_per_step = False
    gen = torch.Generator().manual_seed(5)
    torques = [(torch.rand(3, 8, generator=gen) * 2 - 1) * 10 for _ in range(30)]
    names = ("root_pose", "root_vel", "dof_pos", "dof_vel", "body_q")
    after = {}
    for k, sim in enumerate(sims):
        sim.enable_contact_forces()
        put(sim, z=0.6, dof_vel=0.5)
        for step, t in enumerate(torques):
            sim.set_dof_actuation_force_tensor(t)
            sim.step()
            if step in (0, len(torques) - 1):
                sim.compute_contact_wrenches()
                views = [getattr(sim, n) for n in names] + [sim.to_torch(sim.contact_wrench_buffer())]
                after[k, step] = [v.clone() for v in views]
    moved = (sims[0].dof_pos - torch.as_tensor(sims[0].default_dof_pos_np)).abs().max()
    assert moved > 0.1
    for step, rel in ((0, 1e-5), (len(torques) - 1, 1e-4)):
        for name, a, b in zip((*names, "contact wrench"), after[0, step], after[1, step]):
            scale = max(1.0, b.abs().max().item())
            assert (a - b).abs().max() < rel * scale, (step, name)
    assert after[1, len(torques) - 1][-1].abs().max() > 1.0  # the feet pushed on the ground


@pytest.mark.parametrize("cells, lost", [(8, False), (200, True)])
def test_a_geom_over_more_heightfield_prisms_than_mujoco_keeps_is_counted(cells, lost):
    """A 0.6-m box 1 cm into a 1-m heightfield of ``cells`` x ``cells`` nodes: at 8 the prisms under it fit
    MuJoCo's 50 contacts a pair; at 200 (5 mm cells) MuJoCo Warp drops the rest, and the sim counts it as lost
    contacts (as a full constraint buffer is), not a silent step."""
    import mujoco

    from warpgym.sim.gym_model import CompiledModel
    from warpgym.sim.mjw_sim import MjwSim

    spec = mujoco.MjSpec()
    field = spec.add_hfield(name="ground", size=[0.5, 0.5, 0.01, 0.1], nrow=cells, ncol=cells,
                            userdata=[0.0] * (cells * cells))
    spec.worldbody.add_geom(type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname=field.name)
    box = spec.worldbody.add_body(pos=[0, 0, 0.04])
    box.add_freejoint()
    box.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.3, 0.3, 0.05], mass=1.0)
    sim = MjwSim(CompiledModel(spec.compile(), "hfield"), num_envs=2, device="cpu", njmax=1024, nconmax=256)
    sim.simulate()
    assert (sim.solver_overflows.numpy() > 0).tolist() == [lost, lost]
