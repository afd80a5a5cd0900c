"""Config.overlap: each rollout is drawn by the weights of one update earlier and learnt from next.

On the CPU the two halves run one after the other; the lag, and so every number learnt, is the one
the two CUDA streams run (agents.overlap)."""

from __future__ import annotations

import copy
import os
import sys

import pytest
import torch

sys.path.insert(0, os.path.dirname(__file__))
from point_mass import PointMassVecEnv  # noqa: E402

from agents import Config, OnPolicyRunner  # noqa: E402
from agents.actor_critic import gaussian_log_prob  # noqa: E402

SMALL = dict(net_dims=(16,), horizon_len=10, batch_size=320, repeat_times=2, eval_gap=1e9, save_gap=10**6)


def quiet(env, cfg, **kw):
    return OnPolicyRunner(env, cfg, print_fn=lambda s: None, **kw)


def test_each_rollout_is_learnt_from_one_update_after_the_weights_that_drew_it():
    runner = quiet(PointMassVecEnv(32), Config(**SMALL, overlap=True))
    weights = []  # the learner's weights before each iteration
    original = runner.iterate

    def iterate():
        weights.append(copy.deepcopy(runner.policy.state_dict()))
        return original()

    runner.iterate = iterate
    runner.learn(max_iterations=3)
    pipe = runner.pipeline
    # the behaviour policy holds the weights the learner had when the last iteration began...
    for name, p in pipe.behaviour.named_parameters():
        torch.testing.assert_close(p, weights[-1][name])
        assert not torch.equal(p, runner.policy.state_dict()[name])  # ...not the updated ones
    # and the rollout PPO learns from next carries that policy's log-probabilities and values
    t = pipe.trained
    obs, actions = t.obs.flatten(0, 1), t.actions.flatten(0, 1)
    with torch.no_grad():
        mean = pipe.behaviour.actor(obs)
        log_prob = gaussian_log_prob(actions, mean, pipe.trained_log_std)
        value = pipe.behaviour.value(obs)
    torch.testing.assert_close(log_prob, t.log_probs.flatten(), rtol=1e-4, atol=1e-4)
    torch.testing.assert_close(value, t.values.flatten(), rtol=1e-4, atol=1e-4)
    with torch.no_grad():
        current = gaussian_log_prob(actions, runner.policy.actor(obs), runner.policy.log_std)
    assert not torch.allclose(current, t.log_probs.flatten(), atol=1e-4)


def test_the_first_iteration_collects_the_rollout_its_update_learns_from():
    cfg = Config(**SMALL, overlap=True)
    runner = quiet(PointMassVecEnv(32), cfg)
    history = runner.learn(max_iterations=2)
    per_iter = 32 * cfg.horizon_len
    # two rollouts in the first iteration (one to learn from, one drawn meanwhile), one after
    assert [r["samples"] for r in history] == [2 * per_iter, 3 * per_iter]
    assert runner.pipeline.pending


def test_overlapped_ppo_learns_the_point_mass_as_the_sequential_one_does():
    cfg = Config(net_dims=(32, 32), horizon_len=25, batch_size=400, repeat_times=4, learning_rate=3e-3,
                 eval_gap=1e9, save_gap=10**6, seed=0, overlap=True)
    runner = quiet(PointMassVecEnv(64, seed=0), cfg, eval_env=PointMassVecEnv(16, seed=1))
    history = runner.learn(max_iterations=50)
    returns = [r["return"] for r in history if r["return"] is not None]  # 50-step episodes end every other rollout
    assert returns[0] < -50  # random actions: about -75 per episode
    assert returns[-1] > -20  # as tests/test_agents.py asks of the sequential runner
    assert history[-1]["eval/return"] > -20
    assert all(abs(r["policy/kl"]) < 1.0 for r in history)  # a one-update lag keeps the ratio near 1


def test_a_resumed_overlapped_run_collects_afresh_and_keeps_its_counters(tmp_path):
    cfg = Config(**{**SMALL, "save_gap": 2}, overlap=True)
    a = quiet(PointMassVecEnv(32), cfg, run_dir=str(tmp_path))
    a.learn(max_iterations=3)
    b = quiet(PointMassVecEnv(32), cfg, run_dir=str(tmp_path))
    b.load(str(tmp_path / "checkpoint.pt"))
    assert not b.pipeline.pending  # the rollout in flight was not saved
    assert (b.iteration, b.samples) == (a.iteration, a.samples)
    b.learn(max_iterations=5)
    assert b.iteration == 5
    from agents.logger import read_metrics

    assert [r["iteration"] for r in read_metrics(str(tmp_path))] == [1, 2, 3, 4, 5]


def test_overlap_must_be_a_boolean():
    with pytest.raises(ValueError, match="overlap='yes' must be True or False"):
        Config(overlap="yes").validated()


def test_warpgym_train_overlap_trains_the_ant_and_a_resume_keeps_it(tmp_path):
    import json

    from warpgym.cli import train

    from agents.logger import read_metrics

    run = str(tmp_path / "ant")
    common = ["--horizon-len", "8", "--save-gap", "2", "--no-eval", "--episode-length", "40", "--no-plots"]
    assert train.main(["--task", "Ant", "--device", "cpu", "--num-envs", "8", "--max-iterations", "3",
                       "--run-dir", run, "--overlap", *common]) == 0
    assert json.load(open(os.path.join(run, "config.json")))["overlap"] is True
    rows = read_metrics(run)
    # 64 samples per rollout, and one more rollout in the first iteration, to learn from
    assert [r["samples"] for r in rows] == [128, 192, 256]
    assert all(r["policy/kl"] > 0 for r in rows)  # every iteration moved the policy: PPO ran on every rollout
    assert train.main(["--resume", run, "--max-iterations", "5", "--no-plots"]) == 0
    # the resume collects afresh before its first update (the rollout in flight was not saved)
    assert [r["samples"] for r in read_metrics(run)][-2:] == [256 + 128, 256 + 192]
