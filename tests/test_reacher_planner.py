"""The Reacher planner's bound is only as good as its model: it must be Gymnasium's env, and its search must
keep what it found (benchmarks/learning/reacher_planner.py)."""

import gymnasium as gym
import numpy as np
import pytest

from benchmarks.learning import reacher_planner as rp


@pytest.fixture(scope="module")
def planner():
    env = gym.make("Reacher-v5")
    return env, rp.Planner(env, samples=32, elites=4, threads=1, seed=0)  # checks its kinematics against MuJoCo's


def test_the_planner_predicts_what_gymnasiums_env_pays(planner):
    env, p = planner
    env.reset(seed=5)
    start = p.start_state()
    plan = np.random.default_rng(0).uniform(-1.0, 1.0, (rp.STEPS, 2))
    predicted = p.rewards(start, plan[None])[0]
    env.reset(seed=5)
    paid, rewards = rp.play(env, plan)
    assert len(rewards) == rp.STEPS  # the TimeLimit ends it at the planner's horizon
    # step by step within RK4's reading of the fingertip, and the returns within the script's check
    assert np.abs(np.asarray(rewards) - predicted).max() < 1e-3
    assert abs(paid - predicted.sum()) < rp.PREDICTION_GAP


def test_the_search_keeps_its_best_and_beats_doing_nothing(planner):
    env, p = planner
    env.reset(seed=6)
    start = p.start_state()
    kept = p.plan(start, [2, 6], [3])
    assert list(kept) == ["cem 2", "cem 6", "cem 6 + grad 3"]
    returns = [p.rewards(start, k[None])[0].sum() for k in kept.values()]
    assert returns == sorted(returns)  # a later budget never plays a worse plan
    still = p.rewards(start, np.zeros((1, rp.STEPS, 2)))[0].sum()
    assert returns[-1] > still + 0.5  # it reaches for the target rather than holding still
    assert all(np.abs(k).max() <= 1.0 for k in kept.values())  # within the env's action space


def test_the_report_says_how_many_episodes_reach_the_figure(tmp_path):
    data = {"date": "2026-11-26", "gymnasium": "1.4.0", "mujoco": "3.17.0", "samples": 512, "elites": 32,
            "stages": ["cem 30"], "rows": [{"reset_seed": 0, "returns": {"cem 30": -2.5}, "largest_gap": 1e-4},
                                           {"reset_seed": 1, "returns": {"cem 30": -3.5}, "largest_gap": 2e-4}]}
    path = tmp_path / "reacher_planner.json"
    path.write_text(__import__("json").dumps(data))
    out = rp.report(str(path))
    assert "| cem 30 | -3.00 | -3.00 | -3.50 | -2.50 | 1 of 2 episodes |" in out
    assert "largest difference 2.0e-04" in out


def test_knots_join_into_a_plan_through_them():
    rng = np.random.default_rng(0)
    free = rng.uniform(-1.0, 1.0, (3, rp.STEPS, 2))
    np.testing.assert_allclose(rp.joined(free), free)  # as many knots as steps: every action its own
    knots = rng.uniform(-1.0, 1.0, (3, 10, 2))
    plan = rp.joined(knots)
    assert plan.shape == (3, rp.STEPS, 2)
    np.testing.assert_allclose(plan[:, [0, -1]], knots[:, [0, -1]])  # it starts and ends at the first and last
    assert np.abs(np.diff(plan, axis=1)).max() <= np.abs(np.diff(knots, axis=1)).max()  # and only joins them
