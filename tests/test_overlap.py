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

SMALL = dict(net_dims=(16,), horizon_len=10, minibatch_size=320, repeat_times=2, eval_gap=1e9, save_gap=10**6)


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
    cfg = Config(net_dims=(32, 32), horizon_len=25, minibatch_size=400, repeat_times=4, learning_rate=3e-3,
                 eval_gap=1e9, save_gap=10**6, seed=0, overlap=True)
    runner = quiet(PointMassVecEnv(64, seed=0), cfg, eval_env=PointMassVecEnv(16, seed=1))
    history = runner.learn(max_iterations=50)
    returns = [r["return"] for r in history if r["return"] is not None]  # 50-step episodes end every other rollout
    assert returns[0] < -50  # random actions: about -75 per episode
    assert returns[-1] > -20  # as tests/test_agents.py asks of the sequential runner
    assert history[-1]["eval/return"] > -20
    assert all(abs(r["policy/kl"]) < 1.0 for r in history)  # a one-update lag keeps the ratio near 1


def lagged_rollout(policy, stale, horizon=4, envs=8, seed=0):
    """A rollout drawn by ``stale`` (a copy of ``policy`` with other weights): what the overlapped
    runner hands PPO."""
    from agents.storage import RolloutStorage

    gen = torch.Generator().manual_seed(seed)
    storage = RolloutStorage(horizon, envs, 3, 2, torch.device("cpu"))
    storage.obs.copy_(torch.randn(storage.obs.shape, generator=gen))
    with torch.no_grad():
        actions, log_prob, value, mean = stale.act(storage.obs)
    storage.actions.copy_(actions), storage.log_probs.copy_(log_prob), storage.values.copy_(value)
    storage.means.copy_(mean)
    storage.advantages.copy_(torch.randn(storage.advantages.shape, generator=gen))
    storage.returns.copy_(storage.values + storage.advantages)
    return storage


def test_a_lagged_update_clips_and_measures_kl_against_the_policy_it_starts_from():
    """Decoupled PPO (agents.ppo): the first mini-batch step of a lagged update sees a ratio of 1 and
    no KL, and weights each sample by the proximal over the behaviour probability."""
    from agents.actor_critic import ActorCritic
    from agents.ppo import MAX_BEHAVIOUR_WEIGHT, PPO

    torch.manual_seed(0)
    policy = ActorCritic(3, 2, net_dims=(8,))
    stale = copy.deepcopy(policy)
    with torch.no_grad():
        for p in stale.actor.parameters():
            p.add_(0.3 * torch.randn_like(p))
    storage = lagged_rollout(policy, stale)
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, desired_kl=0.0)
    obs, actions = storage.obs.flatten(0, 1), storage.actions.flatten(0, 1)
    with torch.no_grad():
        prox = gaussian_log_prob(actions, policy.actor(obs), policy.log_std)
    weight = torch.exp(prox - storage.log_probs.flatten()).clamp(max=MAX_BEHAVIOUR_WEIGHT)
    adv = storage.advantages.flatten()
    adv = (adv - adv.mean()) / (adv.std() + 1e-8)

    stats = PPO(copy.deepcopy(policy), cfg, torch.device("cpu")).update(storage, policy.log_std.detach(), 1,
                                                                        lagged=True)
    assert stats["policy/kl"].item() == pytest.approx(0.0, abs=1e-6)  # one step, from the proximal policy
    assert stats["loss/surrogate"].item() == pytest.approx(-(weight * adv).mean().item(), rel=1e-4)
    assert not torch.allclose(weight, torch.ones_like(weight), atol=0.05)  # the lag is real
    stale_stats = PPO(copy.deepcopy(policy), cfg, torch.device("cpu")).update(storage, policy.log_std.detach(), 1)
    assert stale_stats["policy/kl"].item() > 1e-3  # clipped against the behaviour policy, the lag is KL


def test_the_overlapped_learning_rate_follows_the_update_not_the_lag():
    """On an H200 the Ant's overlapped learning rate stayed 2-7x below the sequential one's while the KL
    target saw the lag (docs/benchmarks.md); so did the point mass's (0.09x of the sequential median
    before the decoupled objective)."""
    import statistics

    def median_lr(overlap: bool) -> float:
        cfg = Config(net_dims=(32, 32), horizon_len=25, minibatch_size=400, repeat_times=4, learning_rate=3e-3,
                     eval_gap=1e9, save_gap=10**6, seed=0, overlap=overlap)
        history = quiet(PointMassVecEnv(64, seed=0), cfg).learn(max_iterations=50)
        return statistics.median(r["policy/lr"] for r in history)

    assert median_lr(True) >= median_lr(False) / 3


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
