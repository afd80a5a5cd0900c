"""The legged tasks' sim-to-sim check (warpgym.native.legged, ``warpgym eval`` of a legged run): the same policy
over the same schedule of commands in native MuJoCo (float64, ``mj_step``) and in warpgym's env tracks alike."""

import numpy as np
import pytest
import torch

from warpgym.native.legged import SCHEDULE, commands, native_episodes, warpgym_episodes
from warpgym.tasks.legged import LEGGED
from warpgym.tasks.terms import of_mode

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("pose", ["default", "splayed"])
def test_one_policy_tracks_alike_in_native_mujoco_and_warpgym(pose):
    """Holding the default pose, and a splayed one (hips out, a crouch) that moves the base off its command: the
    tracking errors of the two simulators within 1 % of each other, and no falls in either."""
    task = LEGGED["Go1VelocityFlat-v0"].replace(episode_length_s=4.0)
    action = np.zeros(12, np.float32)
    if pose == "splayed":
        action[[0, 3]], action[[6, 9]] = 3.0, -3.0
    native = native_episodes(task, lambda obs: action, 2)
    ours = warpgym_episodes(task, lambda obs: torch.as_tensor(action).expand(obs.shape[0], 12), 2)
    assert native.falls == ours.falls == 0
    assert abs(native.error_xy / ours.error_xy - 1) < 0.01 and abs(native.error_yaw / ours.error_yaw - 1) < 0.01
    assert native.error_xy > 0.3  # the schedule's commands are not met standing still


def test_the_schedule_cycles_its_commands():
    table = commands(1000, 0.02)
    assert table.shape == (1000, 3) and np.allclose(table[0], SCHEDULE[0]) and np.allclose(table[150], SCHEDULE[1])
    assert len({tuple(c) for c in table}) == len(SCHEDULE)


def test_on_rough_ground_native_mujoco_scans_the_ground_as_warpgym_does_and_tracks_alike():
    """A rough task: native MuJoCo's height scan (``mj_ray``, float64) of each kind of ground, heightfields
    included, against warpgym's observation of the same state; and a policy that reads the scan, on the three kinds
    of boxes (flat, stairs up and down, where the two simulators' contacts agree), tracking alike."""
    import mujoco

    from warpgym.envs.legged import LeggedVecEnv
    from warpgym.native.legged import height_scan, start_patches, start_pose, start_yaws
    from warpgym.tasks.legged.model import compile_task_scene

    task = LEGGED["Go1VelocityRough-v0"].replace(episode_length_s=2.0)
    kinds = len(task.terrain.sub_terrains)
    env = LeggedVecEnv(task, num_envs=kinds, device="cpu", events=of_mode(task.events, "reset"), observation_noise=False)
    starts = start_patches(env.terrain, kinds, level=9)
    state = env.state()
    qpos, idx = state["qpos"].clone(), env.index
    for e, (yaw, (_, origin)) in enumerate(zip(start_yaws(kinds), starts)):
        qpos[e, :7] = torch.as_tensor(start_pose(idx, yaw))
        qpos[e, :3] += torch.as_tensor(origin + [1.3, -0.7, 0.2], dtype=qpos.dtype)  # off the patch's centre
    env.write_state({"qpos": qpos})
    obs, _ = env.observe()
    m = compile_task_scene(task)[0].mjm
    d = mujoco.MjData(m)
    scans = 187
    for e in range(kinds):
        d.qpos[:] = qpos[e].double().numpy()
        mujoco.mj_forward(m, d)
        native = height_scan(mujoco, m, d, idx.root_body, task.height_scan) / 5.0
        ours = obs[e, -scans:].numpy()
        # MuJoCo Warp's bounding-volume rays miss a heightfield where they meet it at its lowest height (the flat
        # floor of the inverted pyramid's pit): 21 rays here read the reach (5 m, 1.0 scaled), in warpgym as in
        # mjlab's own env from this state, where native MuJoCo hits the floor
        missed = (np.abs(ours - 1.0) < 1e-6) & (native < 1.0)
        assert missed.sum() == (21 if e == 4 else 0), (e, int(missed.sum()))
        np.testing.assert_allclose(ours[~missed], native[~missed], atol=2e-5, err_msg=f"kind {e}")
    assert np.ptp(obs[1, -scans:].numpy()) > 0.02  # the stairs at the top level: the scan is not flat
    env.close()

    def reads_the_scan(obs):
        return np.full(12, 0.5 * np.tanh(5.0 * float(np.mean(obs[-scans:])) - 1.0), np.float32)

    native = native_episodes(task, reads_the_scan, 3, level=9)
    ours = warpgym_episodes(task, lambda obs: torch.as_tensor(np.stack([reads_the_scan(o) for o in obs.numpy()])), 3,
                            level=9)
    assert native.falls == ours.falls == 0 and list(native.falls_by_kind) == ["flat", "pyramid_stairs",
                                                                               "pyramid_stairs_inv"]
    assert abs(native.error_xy / ours.error_xy - 1) < 0.01 and abs(native.error_yaw / ours.error_yaw - 1) < 0.01


def test_tracking_means_weigh_each_step_and_split_by_kind_of_ground():
    """Both replays' tracking (warpgym.native.legged.tracking): every step of every episode weighs the same, so a
    fallen episode's few steps count for little; per kind, only that kind's episodes."""
    from types import SimpleNamespace

    from warpgym.native.legged import tracking

    ground = SimpleNamespace(grid=SimpleNamespace(sub_terrains=[("flat", None), ("stairs", None)]))
    sums = [[10.0, 1.0], [2.0, 2.0], [30.0, 3.0]]  # error sums (xy, yaw) of three episodes
    steps = [100, 10, 100]
    got = tracking(sums, steps, [False, True, False], ground, kinds=[0, 1, 0])
    assert (got.error_xy, got.error_yaw) == pytest.approx((42.0 / 210, 6.0 / 210))
    assert got.errors_by_kind == {"flat": pytest.approx((0.2, 0.02)), "stairs": pytest.approx((0.2, 0.2))}
    assert got.falls_by_kind == {"flat": (0, 2), "stairs": (1, 1)} and (got.falls, got.episodes) == (1, 3)
    assert tracking(sums, steps, [False] * 3).errors_by_kind is None  # flat ground: no kinds
