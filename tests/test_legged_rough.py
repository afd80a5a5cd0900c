"""The rough-ground tasks (Go1VelocityRough-v0, G1VelocityRough-v0) as envs: mjlab's observation widths, worlds
starting on their patches, the height scan seeing the ground, the curriculum moving a world that walked, the
ground's bound, the Go1's thighs ending an episode where tilt does not, and upright measured against the slope."""

import math

import numpy as np
import pytest
import torch

from warpgym.envs.legged import LeggedVecEnv
from warpgym.tasks.legged.levels import bounds

N = 8  # one world a kind, and one more on the first (the flat kind's proportion is the largest)


@pytest.fixture(scope="module")
def go1():
    env = LeggedVecEnv("Go1VelocityRough-v0", num_envs=N, device="cpu", seed=0, events={"push_robot": None}, observation_noise=False)
    env.reset(seed=0)
    yield env
    env.close()


def kinds_levels(env):
    t = env._levels
    return t.kind.numpy().copy(), t.level.numpy().copy(), env.terrain.origins


def teleport(env, world, xyz, quat=(1.0, 0.0, 0.0, 0.0)):
    state = env.state()
    qpos = state["qpos"].clone()
    qpos[world, :3] = torch.tensor(xyz)
    qpos[world, 3:7] = torch.tensor(quat)
    qvel = torch.zeros_like(state["qvel"])
    env.write_state({"qpos": qpos, "qvel": qvel})


def test_mjlabs_widths_and_terms():
    g1 = LeggedVecEnv("G1VelocityRough-v0", num_envs=2, device="cpu", seed=0)
    obs, info = g1.reset(seed=0)
    # mjlab 1.6's rough envs: the flat widths plus the 17 x 11 height scan in both (Go1 48 / 72, G1 99 / 111)
    assert obs.shape == (2, 99 + 187) and info["critic_obs"].shape == (2, 111 + 187)
    g1.close()


def test_worlds_start_on_their_patches_one_kind_each_levels_up_to_five(go1):
    obs, info = go1.reset(seed=0)
    kinds, levels, origins = kinds_levels(go1)
    assert obs.shape == (N, 48 + 187) and info["critic_obs"].shape == (N, 72 + 187)
    assert sorted(kinds.tolist()) == [0, 0, 1, 2, 3, 4, 5, 6] and levels.min() >= 0 and levels.max() <= 5
    root = go1.sim.to_torch(go1.sim.d.qpos)[:, :2].numpy()
    # mjlab's reset: the patch's start plus up to 0.5 m in x and y
    assert np.abs(root - origins[levels, kinds][:, :2]).max() <= 0.5 + 1e-5
    assert torch.equal(go1.info["terrain_level"].cpu(), torch.as_tensor(levels))


def test_the_height_scan_is_the_base_height_over_level_ground(go1):
    go1.reset(seed=0)
    kinds, levels, origins = kinds_levels(go1)
    w = int(np.flatnonzero(kinds == 0)[0])  # the flat kind: the ground at z = 0 everywhere on the patch
    _, info = go1.observe()
    trunk_z = float(go1.sim.to_torch(go1.sim.d.xpos)[w, go1.index.root_body, 2])
    scan = info["critic_obs"][w, 48:48 + 187].numpy()
    # mjlab scales the heights by 1 / 5 m, the scan's reach
    np.testing.assert_allclose(scan, trunk_z / 5.0, atol=1e-5)
    # a world on stairs sees steps: its heights take several values (level 0 has steps of 0 m: pick a higher one)
    teleport(go1, 1, (*(origins[9, 1][:2] + [1.5, 1.0]), origins[9, 1][2] + 0.4))
    _, info = go1.observe()
    assert len(np.unique(np.round(info["critic_obs"][1, 48:48 + 187].numpy(), 3))) > 3
    go1.reset(seed=0)


def test_a_world_that_walked_half_a_patch_moves_up_a_level_when_its_episode_ends(go1):
    go1.reset(seed=0)
    go1.step(torch.zeros(N, go1.num_actions))  # past the first reset, which moves no level
    kinds, levels, origins = kinds_levels(go1)
    w = int(np.argmin(levels))
    start = origins[levels[w], kinds[w]]
    teleport(go1, w, (start[0] + 5.0, start[1], start[2] + 0.4))  # 5 m from its start: more than 4 m
    state = go1.state()
    length = state["length"].clone()
    length[w] = go1.max_episode_steps - 1
    go1.write_state({"length": length})
    _, _, terminated, truncated, info = go1.step(torch.zeros(N, go1.num_actions))
    assert bool(truncated[w]) and not bool(terminated[w])
    assert int(go1.info["terrain_level"][w]) == levels[w] + 1
    # the curriculum state training logs (curriculum/terrain_level): every world's level, this one's move included
    assert float(go1.curriculum()["terrain_level"]) == pytest.approx((levels.sum() + 1) / N)
    go1.reset(seed=0)


def test_leaving_the_ground_ends_the_episode_as_a_time_out(go1):
    go1.reset(seed=0)
    half_x, _ = bounds(go1.terrain)
    teleport(go1, 3, (half_x + 0.5, 0.0, 2.0))  # over the border's edge, less its margin
    _, _, terminated, truncated, _ = go1.step(torch.zeros(N, go1.num_actions))
    assert bool(truncated[3]) and not bool(terminated[3])
    assert not truncated[[0, 1, 2, 4]].any()
    go1.reset(seed=0)


def test_the_go1s_thighs_on_the_ground_end_an_episode_its_tilt_does_not(go1):
    go1.reset(seed=0)
    kinds, levels, origins = kinds_levels(go1)
    flat = np.flatnonzero(kinds == 0)
    a, b = int(flat[0]), int(flat[1])
    # a: on its side, high in the air (tilted 90 degrees, touching nothing); b: its body pressed into the ground
    roll = (math.cos(math.pi / 4), math.sin(math.pi / 4), 0.0, 0.0)
    teleport(go1, a, (*origins[levels[a], 0][:2], 2.0), roll)
    teleport(go1, b, (*origins[levels[b], 0][:2], 0.05))
    _, _, terminated, _, info = go1.step(torch.zeros(N, go1.num_actions))
    assert not bool(terminated[a]) and bool(terminated[b])
    go1.reset(seed=0)


def test_upright_is_measured_against_the_slope_under_the_base(go1):
    go1.reset(seed=0)
    kinds, _, origins = kinds_levels(go1)
    w = int(np.flatnonzero(kinds == 3)[0])  # a pyramid slope; at the top level its sides rise at 45 degrees
    o = origins[9, 3]
    teleport(go1, w, (o[0] + 2.0, o[1], o[2] + 0.5))  # over the side, 2 m from the top
    go1.observe()
    normal = go1.sim.to_torch(go1._state.terrain_normal).numpy()
    tilt = math.degrees(math.acos(float(normal[w, 2])))
    assert 30.0 < tilt < 60.0
    level = [int(i) for i in np.flatnonzero(kinds == 0)]
    np.testing.assert_allclose(normal[level], [[0.0, 0.0, 1.0]] * len(level), atol=1e-5)
    go1.reset(seed=0)


@pytest.mark.parametrize("task", ["Go1VelocityRough-v0", "G1VelocityRough-v0"])
def test_the_scene_and_ground_compile_to_mjlabs_model(task):
    """MuJoCo 3.17's compile of the rough scene built from the robot's own file, with the generated ground, against mjlab's env's own model
    for the same ground seed (tests/data/legged/rough_models.npz, ``python -m benchmarks.physics.mjlab_side models``;
    CI records it afresh): every field, the robot's geoms by name and the ground's as a set (the two name the
    ground's geoms in different orders)."""
    import dataclasses
    import os

    import mujoco

    from warpgym.tasks.legged import LEGGED
    from warpgym.tasks.legged.model import compile_task_scene

    folder = os.environ.get("WARPGYM_MJLAB_REFERENCE") or os.path.join(os.path.dirname(__file__), "data", "legged")
    ref = np.load(os.path.join(folder, "rough_models.npz"))
    m = compile_task_scene(dataclasses.replace(LEGGED[task], terrain_seed=int(ref["seed"])))[0].mjm

    def field(name):
        obj = m
        for part in name.split("."):
            obj = getattr(obj, part)
        return np.asarray(obj, np.float64)

    prefix = f"{task}/"
    for key in (k for k in ref.files if k.startswith(prefix + "model/")):
        name = key[len(prefix) + 6:]
        theirs = ref[key].astype(np.float64)
        assert field(name).shape == theirs.shape, name
        # the file writes numbers to 6 significant digits: the actuators' gains differ by up to 3e-6
        assert np.all(np.abs(field(name) - theirs) <= 1e-7 + 5e-6 * np.abs(theirs)), name
    names = [mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, i) or "" for i in range(m.ngeom)]
    theirs_names = [str(n) for n in ref[prefix + "geom_names"]]
    robot = [i for i, n in enumerate(theirs_names) if not n.startswith("terrain_")]
    ground_rows = [i for i, n in enumerate(theirs_names) if n.startswith("terrain_")]
    ours_ground = [i for i, n in enumerate(names) if n.startswith("terrain_")]
    assert len(ground_rows) == len(ours_ground) > 500
    for key in (k for k in ref.files if k.startswith(prefix + "geom/")):
        gname = key[len(prefix) + 5:]
        theirs, ours = ref[key].astype(np.float64), np.asarray(getattr(m, gname), np.float64)
        rows = [names.index(theirs_names[i]) for i in robot]
        assert np.allclose(ours[rows], theirs[robot], atol=1e-7, rtol=5e-6), gname
        if gname == "geom_bodyid":
            continue
        # the ground's geoms in one order on both sides: by position, then size
        pos = np.round(np.asarray(m.geom_pos)[ours_ground], 4)
        their_pos = np.round(ref[prefix + "geom/geom_pos"][ground_rows], 4)
        order_ours = np.lexsort((*pos.T[::-1], np.asarray(m.geom_size)[ours_ground].sum(1)))
        order_theirs = np.lexsort((*their_pos.T[::-1], ref[prefix + "geom/geom_size"][ground_rows].sum(1)))
        assert np.allclose(ours[ours_ground][order_ours], theirs[ground_rows][order_theirs], atol=1e-5, rtol=1e-5), \
            gname
    ours_sensors = [[mujoco.mj_id2name(m, int(m.sensor_objtype[i]), int(m.sensor_objid[i])) or "",
                     mujoco.mj_id2name(m, int(m.sensor_reftype[i]), int(m.sensor_refid[i])) or ""]
                    for i in range(m.nsensor)]
    assert ours_sensors == ref[prefix + "sensor_objects"].tolist()


def test_ended_episodes_report_their_level_and_drawings_compile_the_same_ground(go1):
    from warpgym.tasks.legged import LEGGED
    from warpgym.tasks.legged.model import compile_task_scene

    go1.reset(seed=0)
    go1.step(torch.zeros(N, go1.num_actions))  # past the first reset, which moves no level
    before = kinds_levels(go1)[1]
    state = go1.state()
    length = state["length"].clone()
    length[:] = go1.max_episode_steps - 1
    command = torch.zeros_like(state["command"])
    command[:, 0] = 1.0  # asked 1 m/s for 20 s: standing still, every world walked less than half of it
    go1.write_state({"length": length, "command": command})
    _, _, _, truncated, info = go1.step(torch.zeros(N, go1.num_actions))
    assert truncated.all()
    assert info["episode"]["terrain_level"].cpu().tolist() == np.maximum(before - 1, 0).tolist()
    # drawings and native MuJoCo (tests/test_native_legged.py) compile the same scene and ground as the env
    model, ground = compile_task_scene(LEGGED["Go1VelocityRough-v0"])
    assert model.mjm.ngeom == go1.sim.mjm.ngeom > 500 and ground is not None
    go1.reset(seed=0)
