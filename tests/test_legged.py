"""The legged velocity tasks beside the judge's comparison (tests/test_legged_judge.py): what a user meets in
them. Their place in the registry and Gymnasium, a wrong keyword's one line, NaN actions counted and not
propagated, the state written back, seeds, staggered starts, pushes and the command curriculum."""

import math

import gymnasium as gym
import pytest
import torch

import warpgym  # noqa: F401  (registers the ids)
from warpgym.envs.legged import LeggedVecEnv
from warpgym.tasks.legged import LEGGED
from warpgym.tasks.registry import task_entry, task_names

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def go1():
    env = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=4, device="cpu", seed=3)
    yield env
    env.close()


def test_the_tasks_are_in_the_registry_and_gymnasium():
    assert task_names("legged") == ["Go1VelocityFlat-v0", "G1VelocityFlat-v0", "Go1VelocityRough-v0",
                                    "G1VelocityRough-v0", "VelocityFlat-v0", "VelocityRough-v0"]
    for name, task in LEGGED.items():
        entry = task_entry(name)
        assert entry.family == "legged" and entry.gym_id == f"warpgym/{name}" and entry.episode_length == 1000
        ground = "Rough" if "Rough" in name else "Flat"
        robot = name.split("Velocity")[0]
        assert task.mirrors == f"Mjlab-Velocity-{ground}" + (f"-Unitree-{robot}" if robot else "")
    envs = gym.make_vec("warpgym/G1VelocityFlat-v0", num_envs=2, device="cpu", events={"push_robot": None})
    obs, info = envs.reset(seed=0)
    # mjlab's widths: the G1's policy sees 99 entries and its critic 111 (the Go1's 48 and 72)
    assert obs.shape == (2, 99) and info["critic_obs"].shape == (2, 111) and envs.num_actions == 29
    envs.close()


def test_widths_and_terms(go1):
    obs, info = go1.reset(seed=0)
    assert obs.shape == (4, 48) and info["critic_obs"].shape == (4, 72)
    obs, reward, terminated, truncated, info = go1.step(torch.zeros(4, 12))
    terms = sum(v for k, v in info.items() if k.startswith("reward_"))
    assert torch.allclose(terms, reward, atol=1e-6)
    # standing still at the default pose, upright, on command 0 or not: the posture and upright terms are near
    # their best, each weight * dt = 0.02
    assert float(info["reward_upright"].min()) > 0.019


@pytest.mark.parametrize("changes, words", [
    ({"lin_vel_x": (1.0, -1.0)}, "lin_vel_x=(1.0, -1.0) must be a (low, high) pair"),
    ({"events": {"push_robot": {"interval": (-1.0, 3.0)}}}, "interval=(-1.0, 3.0) must be (low, high) seconds"),
    ({"events": {"reset_base": {"params": {"yaw": (3.0, -3.0)}}}}, "yaw=(3.0, -3.0) must be a (low, high) range"),
    ({"events": {"push_robot": {"mode": "sometimes"}}}, "mode='sometimes' must be one of"),
    ({"foot_sites": ("robot/FR", "robot/XX", "robot/RR", "robot/RL")}, "has no site 'robot/XX'; its sites are"),
    ({"rewards": {"fly": 1.0}}, "rewards: no term 'fly'; its terms are"),
    ({"rewards": {"pose": {"params": {"std_walking": 0.3}}}}, "std_walking=0.3"),
    ({"flying": True}, "has no argument(s) ['flying']"),
    ({"rel_standing_envs": 1.5}, "rel_standing_envs=1.5 is a share of the worlds"),
])
def test_a_wrong_keyword_is_one_line_that_names_it(changes, words):
    with pytest.raises(ValueError) as e:
        LeggedVecEnv("Go1VelocityFlat-v0", num_envs=1, device="cpu", **changes)
    assert words in str(e.value) and "\n" not in str(e.value)


def test_nan_actions_are_counted_and_never_reach_the_state(go1):
    go1.reset(seed=1)
    before = int(go1.fault_counters()["nan_actions"])
    actions = torch.zeros(4, 12)
    actions[1, 3] = float("nan")
    actions[2, :] = float("inf")
    obs, reward, *_ = go1.step(actions)
    assert int(go1.fault_counters()["nan_actions"]) - before == 13
    assert torch.isfinite(obs).all() and torch.isfinite(reward).all() and torch.isfinite(go1.sim.dof_pos).all()
    assert float(go1.actions[1, 3]) == 0.0  # applied (and observed) as 0


def test_a_written_state_replays_step_for_step(go1):
    go1.reset(seed=2)
    for _ in range(5):
        go1.step(torch.rand(4, 12) * 2 - 1)
    # no push or new command within the step (their draws, and the policy's noise, come from the step's random state)
    saved = {**go1.state(), "push_robot_time_left": torch.full((4,), 100.0),
             "command_time_left": torch.full((4,), 100.0)}
    actions = torch.rand(4, 12) * 2 - 1
    go1.write_state(saved)
    first = go1.step(actions)[4]["critic_obs"].clone()
    go1.write_state(saved)
    again = go1.step(actions)[4]["critic_obs"]
    assert torch.allclose(first, again, atol=1e-6) and not torch.allclose(first, go1.step(actions)[4]["critic_obs"])
    with pytest.raises(ValueError, match="write_state: no state"):
        go1.write_state({"speed": torch.zeros(4)})
    with pytest.raises(ValueError, match="has shape"):
        go1.write_state({"command": torch.zeros(3, 3)})


def test_a_seed_decides_every_draw():
    def run(seed):
        env = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=4, device="cpu", seed=seed)
        obs, _ = env.reset(seed=seed)
        out = [obs.clone()]
        for _ in range(3):
            out.append(env.step(torch.zeros(4, 12))[0].clone())
        friction = env.state()["foot_friction"]
        env.close()
        return torch.stack(out), friction

    (a, fa), (b, fb), (c, fc) = run(5), run(5), run(6)
    assert torch.equal(a, b) and torch.equal(fa, fb)
    assert not torch.allclose(a, c) and not torch.allclose(fa, fc)


def test_staggered_starts_spread_the_time_limits(go1):
    obs, info = go1.stagger_episodes()
    assert obs.shape == (4, 48) and info["critic_obs"].shape == (4, 72)
    lengths = go1.episode_steps.tolist()
    assert len(set(lengths)) > 1 and all(0 <= n < 1000 for n in lengths)
    go1.reset()
    assert go1.episode_steps.tolist() == [0, 0, 0, 0]


def test_a_push_changes_the_base_velocity_within_its_ranges():
    """A push due this step adds a draw within mjlab's ranges to the base's world velocity: from rest (no gravity
    in play within the step for the frozen check, the push is the only change), the base's linear velocity after
    the step differs from an unpushed copy's by at most the range's bound."""
    calm = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=8, device="cpu", seed=4, events={"push_robot": None})
    pushed = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=8, device="cpu", seed=4)
    assert "push_robot_time_left" not in calm.state_keys  # no push, no timer
    calm.reset(seed=4)
    pushed.reset(seed=4)
    state = calm.state()
    pushed.write_state({**state, "push_robot_time_left": torch.zeros(8)})  # due now
    calm.write_state(state)
    actions = torch.zeros(8, 12)
    calm.step(actions)
    pushed.step(actions)
    dv = pushed.sim.dof_vel[:, :3] - calm.sim.dof_vel[:, :3]
    bound = torch.tensor([0.5, 0.5, 0.4]) + 1e-4
    assert (dv.abs() <= bound).all() and dv.abs().max() > 0.05
    # and the next push is drawn 1-3 s ahead
    left = pushed.state()["push_robot_time_left"]
    assert ((left >= 1.0) & (left <= 3.0)).all()
    calm.close()
    pushed.close()


def test_the_command_curriculum_widens_the_ranges_at_its_steps():
    env = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=256, device="cpu", seed=9, rel_standing_envs=0.0,
                       rel_heading_envs=0.0, rel_forward_envs=0.0)
    env.reset(seed=9)
    early = env.state()["command"]
    env.write_state({"step_count": 10000 * 24})
    env.reset(seed=10)
    late = env.state()["command"]
    env.close()
    assert early[:, 0].max() <= 1.0 and early[:, 2].abs().max() <= 0.5
    # the last stage: x in [-2, 3] and a yaw rate in [-0.7, 0.7]
    assert late[:, 0].max() > 2.0 and late[:, 0].min() < -1.5 and 0.5 < late[:, 2].abs().max() <= 0.7
    assert math.isclose(env.task.episode_length_s, 20.0)


def test_a_clip_draws_the_robot_where_it_stands():
    """``warpgym play RUN --gif`` of a legged task draws its scene's collision geometry (the file has no visual
    meshes): the robot fills part of the frame, and a crouched pose draws another picture."""
    import numpy as np

    from warpgym.media.legged import LeggedView
    from warpgym.tasks.legged.model import resolve

    task = LEGGED["Go1VelocityFlat-v0"]
    view = LeggedView(task, 160, 120)
    idx = resolve(task, view.model)
    qpos = view.model.key_qpos[0].copy()
    standing = view.render(qpos)
    qpos[idx.joint_qpos] += 0.5
    crouched = view.render(qpos)
    view.close()
    assert standing.shape == (120, 160, 3) and standing.std() > 10
    assert np.abs(standing.astype(int) - crouched.astype(int)).mean() > 1.0
