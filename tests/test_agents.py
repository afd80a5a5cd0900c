"""The PPO pieces against hand-computed values, learning on a torch-only env, and the dependency rule."""

import ast
import os
import statistics
import subprocess
import sys
import time

import numpy as np
import pytest
import torch

from agents import Config, OnPolicyRunner, RunningMeanStd

from warpgym.tasks.presets import PRESETS
from agents.actor_critic import ActorCritic, gaussian_kl, gaussian_log_prob
from agents.checkpoint import load, policy_from_checkpoint, save_atomic, with_normalizer
from agents.logger import read_metrics
from agents.ppo import adapted_lr, surrogate_loss, value_loss
from agents.loop import progress_line
from agents.storage import compute_gae
from point_mass import PointMassVecEnv

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_gae_with_termination_and_truncation_by_hand():
    g, lam = 0.9, 0.5
    # one env, three steps: step 1 ends by termination; step 2 ends by truncation whose bootstrap
    # (g * V(final_obs) = 0.9 * 10) is already folded into its reward, as the runner does.
    rewards = torch.tensor([[1.0], [2.0], [3.0 + g * 10.0]])
    values = torch.tensor([[0.5], [1.5], [2.5]])
    dones = torch.tensor([[0.0], [1.0], [1.0]])
    last = torch.tensor([7.0])  # the value after the horizon belongs to a new episode: unused
    adv, ret = compute_gae(rewards, values, dones, last, g, lam)
    d2 = 12.0 - 2.5
    d1 = 2.0 - 1.5
    d0 = 1.0 + g * 1.5 - 0.5
    expected = torch.tensor([[d0 + g * lam * d1], [d1], [d2]])
    torch.testing.assert_close(adv, expected)
    torch.testing.assert_close(ret, expected + values)


def test_gae_bootstraps_the_horizon_when_no_episode_ended():
    adv, _ = compute_gae(torch.tensor([[1.0]]), torch.tensor([[2.0]]), torch.tensor([[0.0]]),
                         torch.tensor([4.0]), 0.99, 0.95)
    assert adv.item() == pytest.approx(1.0 + 0.99 * 4.0 - 2.0)


def test_clipped_surrogate_and_value_losses_by_hand():
    old = torch.log(torch.tensor([0.5, 0.5, 0.5]))
    new = torch.log(torch.tensor([0.75, 0.25, 0.55]))  # ratios 1.5, 0.5, 1.1
    adv = torch.tensor([1.0, -1.0, 2.0])
    # min(r*A, clip(r, 0.8, 1.2)*A) per sample: min(1.5, 1.2), min(-0.5, -0.8), min(2.2, 2.2)
    expected = -(1.2 + -0.8 + 2.2) / 3
    assert surrogate_loss(new, old, adv, 0.2).item() == pytest.approx(expected, rel=1e-5)
    v = torch.tensor([3.0, 0.0])
    v_old = torch.tensor([1.0, 0.0])
    ret = torch.tensor([1.0, 1.0])
    # env 0: unclipped (3-1)^2 = 4, clipped 1+0.2 -> (1.2-1)^2 = 0.04, max 4; env 1: 1 and 1
    assert value_loss(v, v_old, ret, 0.2).item() == pytest.approx((4.0 + 1.0) / 2)
    assert value_loss(v, v_old, ret, 0.0).item() == pytest.approx((4.0 + 1.0) / 2)


def test_gaussian_log_prob_and_kl_against_torch_distributions():
    gen = torch.Generator().manual_seed(0)
    mean, log_std = torch.randn(5, 3, generator=gen), torch.randn(3, generator=gen) * 0.3
    x = torch.randn(5, 3, generator=gen)
    dist = torch.distributions.Normal(mean, log_std.exp())
    torch.testing.assert_close(gaussian_log_prob(x, mean, log_std), dist.log_prob(x).sum(-1))
    mean2, log_std2 = mean + 0.1, log_std - 0.2
    dist2 = torch.distributions.Normal(mean2, log_std2.exp())
    torch.testing.assert_close(gaussian_kl(mean, log_std, mean2, log_std2),
                               torch.distributions.kl_divergence(dist, dist2).sum(-1))


def test_adaptive_learning_rate_rule():
    lr = torch.tensor(1e-3)
    assert adapted_lr(lr, torch.tensor(0.1), 0.01).item() == pytest.approx(1e-3 / 1.5)
    assert adapted_lr(lr, torch.tensor(0.001), 0.01).item() == pytest.approx(1.5e-3)
    assert adapted_lr(lr, torch.tensor(0.01), 0.01).item() == pytest.approx(1e-3)
    assert adapted_lr(torch.tensor(1e-2), torch.tensor(0.0), 0.01).item() == pytest.approx(1e-2)


def test_an_update_logs_the_mean_and_peak_of_its_mini_batches_rates_and_kls(monkeypatch):
    """policy/lr is the rate after the last mini-batch; policy/lr_mean, policy/lr_max and policy/kl_max read
    every mini-batch of the update, where the KL rule may have swung the rate and come back."""
    import agents.ppo as ppo_module

    kls, rates = [], []
    rule = ppo_module.adapted_lr

    def watched(lr, kl, desired_kl):
        kls.append(kl.item())
        return rule(lr, kl, desired_kl)

    monkeypatch.setattr(ppo_module, "adapted_lr", watched)
    cfg = Config(net_dims=(16,), horizon_len=4, minibatch_size=8, repeat_times=3, learning_rate=5e-3, seed=1,
                 eval_gap=1e9)
    runner = OnPolicyRunner(PointMassVecEnv(8, seed=1), cfg, print_fn=lambda s: None)
    step = runner.ppo.optimizer.step
    monkeypatch.setattr(runner.ppo.optimizer, "step", lambda *a, **k: (rates.append(runner.ppo.lr.item()),
                                                                       step(*a, **k))[1])
    history = runner.learn(max_iterations=3)
    n = 3 * 4  # an update: repeat_times passes of 4 mini-batches
    assert len(rates) == len(kls) == 3 * n
    for i, row in enumerate(history):
        mine, kl = rates[i * n:(i + 1) * n], kls[i * n:(i + 1) * n]
        assert row["policy/lr"] == pytest.approx(mine[-1])
        assert row["policy/lr_mean"] == pytest.approx(sum(mine) / n)
        assert row["policy/lr_max"] == pytest.approx(max(mine))
        assert row["policy/kl_max"] == pytest.approx(max(kl)) and row["policy/kl"] == pytest.approx(sum(kl) / n)
    assert len(set(mine)) > 1  # the rule moved the rate within an update


def test_an_annealed_learning_rate_falls_linearly_to_zero_over_the_budget_and_resumes_where_it_was(tmp_path):
    """Config.anneal_lr: iteration k of n learns at learning_rate * (1 - (k - 1) / n) (the factor is set
    before each update), with the KL rule too (its rate, scaled), and a resumed run goes on down the line."""
    base = dict(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=2, learning_rate=1e-3, eval_gap=1e9,
                save_gap=2)
    fixed = OnPolicyRunner(PointMassVecEnv(8), Config(**base, desired_kl=0.0, anneal_lr=True), run_dir=str(tmp_path),
                           print_fn=lambda s: None)
    first = fixed.learn(max_iterations=4)
    assert [r["policy/lr"] for r in first] == pytest.approx([1e-3, 7.5e-4, 5e-4, 2.5e-4])
    resumed = OnPolicyRunner(PointMassVecEnv(8), Config(**base, desired_kl=0.0, anneal_lr=True),
                             print_fn=lambda s: None)
    resumed.load(str(tmp_path / "checkpoint.pt"))
    assert [r["policy/lr"] for r in resumed.learn(max_iterations=8)] == pytest.approx([5e-4, 3.75e-4, 2.5e-4, 1.25e-4])

    def rates(anneal):
        runner = OnPolicyRunner(PointMassVecEnv(8), Config(**base, seed=3, anneal_lr=anneal), print_fn=lambda s: None)
        return [r["policy/lr"] for r in runner.learn(max_iterations=4)], runner.ppo.lr_free.item()

    adaptive, _ = rates(False)
    annealed, free = rates(True)
    # the same KL rule picks the same rates (the decay touches the step size, so the KLs drift only a little)
    assert annealed[0] == pytest.approx(adaptive[0])
    assert annealed[-1] == pytest.approx(free * 0.25) and free != pytest.approx(1e-3)


def test_normalizer_matches_numpy_over_batches():
    rng = np.random.default_rng(0)
    batches = [rng.normal(3.0, 2.0, size=(n, 4)).astype(np.float32) for n in (7, 100, 33)]
    norm = RunningMeanStd(4, clip=100.0)
    for b in batches:
        norm.update(torch.from_numpy(b))
    allx = np.concatenate(batches)
    np.testing.assert_allclose(norm.mean.numpy(), allx.mean(0), rtol=1e-5)
    np.testing.assert_allclose(norm.var.numpy(), allx.var(0), rtol=1e-4)
    assert norm.count.item() == len(allx)
    out = norm(torch.from_numpy(allx)).numpy()
    np.testing.assert_allclose(out.mean(0), 0.0, atol=1e-4)
    assert RunningMeanStd(1, clip=5.0)(torch.tensor([[1e6]])).item() == 5.0


def test_normalizer_keeps_its_statistics_once_it_holds_until_observations():
    """rsl_rl's ``until``: the batch that reaches the count is learnt whole, the ones after it not at all; the
    runner's normaliser stops so in a run (Config.normalize_until), and 0 learns throughout."""
    rng = np.random.default_rng(1)
    batches = [torch.from_numpy(rng.normal(m, 1.0, size=(60, 3)).astype(np.float32)) for m in (0.0, 1.0, 9.0)]
    frozen, free = RunningMeanStd(3, until=100), RunningMeanStd(3)
    for b in batches:
        frozen.update(b)
        free.update(b)
    learnt = torch.cat(batches[:2]).numpy()
    np.testing.assert_allclose(frozen.mean.numpy(), learnt.mean(0), rtol=1e-5)
    np.testing.assert_allclose(frozen.var.numpy(), learnt.var(0), rtol=1e-4)
    assert frozen.count.item() == 120 and free.count.item() == 180 and free.mean.mean().item() > 3.0

    cfg = Config(net_dims=(16,), horizon_len=4, minibatch_size=32, seed=0, normalize_until=40, eval_gap=1e9)
    runner = OnPolicyRunner(PointMassVecEnv(8, seed=0), cfg, print_fn=lambda s: None)
    runner.learn(max_iterations=3)
    # the first observations (8), then the first rollout (32): 40, where it stops
    assert runner.normalizer.count.item() == 40
    with pytest.raises(ValueError, match="normalize_until=-1"):
        Config(normalize_until=-1).validated()


def test_config_validation_names_the_value_and_the_fix():
    with pytest.raises(ValueError, match="gamma=1.5"):
        Config(gamma=1.5).validated()
    with pytest.raises(ValueError, match="horizon_len=0"):
        Config(horizon_len=0).validated()
    with pytest.raises(ValueError, match="unknown config field"):
        Config().replace(lr=1.0)
    with pytest.raises(ValueError, match="does not divide"):
        Config(minibatch_size=300, horizon_len=16).check_batch(64)
    with pytest.raises(ValueError, match="exceeds"):
        Config(minibatch_size=4096, horizon_len=16).check_batch(64)
    assert Config(minibatch_size=256, horizon_len=16).check_batch(64) == 4
    assert Config.from_preset(PRESETS["Humanoid"]).net_dims == (400, 200, 100)


def test_ppo_learns_a_point_mass_within_seconds():
    env, ev = PointMassVecEnv(64, seed=0), PointMassVecEnv(16, seed=1)
    cfg = Config(net_dims=(32, 32), horizon_len=25, minibatch_size=400, repeat_times=4, learning_rate=3e-3,
                 eval_gap=1e9, save_gap=10**6, seed=0)
    runner = OnPolicyRunner(env, cfg, eval_env=ev, print_fn=lambda s: None)
    history = runner.learn(max_iterations=50)
    first = next(r["return"] for r in history if r["return"] is not None)
    # random actions leave the mass ~1.4 m out on average (about -75 per episode); a good policy
    # brings it home in a few steps and scores better than -20
    assert first < -50
    assert history[-1]["return"] > -20
    assert history[-1]["eval/return"] > -20


def test_a_large_entropy_bonus_raises_the_noise_but_never_past_max_noise_std():
    """``max_noise_std`` bounds what an entropy bonus does to the noise: without it a strong bonus on the point
    mass pushes the std above 1.5 within a few updates; with 1.2 it ends at 1.2, never above, after every step;
    a negative bound is one line naming it."""
    def final_std(**bound):
        env = PointMassVecEnv(64, seed=0)
        cfg = Config(net_dims=(32, 32), horizon_len=25, minibatch_size=400, repeat_times=4, learning_rate=3e-2,
                     entropy_coef=1.0, desired_kl=0, eval_gap=1e9, save_gap=10**6, seed=0, **bound)
        runner = OnPolicyRunner(env, cfg, print_fn=lambda s: None)
        logged = max(r["policy/noise_std"] for r in runner.learn(max_iterations=8))
        return float(runner.policy.log_std.detach().exp().max()), logged

    free, _ = final_std()
    assert free > 1.5
    bounded, peak_logged = final_std(max_noise_std=1.2)
    assert bounded == pytest.approx(1.2, rel=1e-5) and peak_logged <= 1.2 + 1e-5
    with pytest.raises(ValueError, match="max_noise_std=-1"):
        Config(max_noise_std=-1).validated()


def test_a_captured_rollout_replays_beside_after_each_step_only_where_it_was_captured_step_by_step():
    """The collector replays either capture through one call (agents.collect): the step's graph ``horizon``
    times with the hook after each step, then the finishing graph; a rollout captured whole replays as one
    graph and cannot call the hook between its steps (a background evaluation then queues its own)."""
    from agents.collect import StepGraphs, WholeRollout

    calls = []

    class Graph:  # what a CUDA graph offers the collector: replay()
        def __init__(self, name):
            self.name = name

        def replay(self):
            calls.append(self.name)

    StepGraphs(Graph("step"), Graph("finish"), 3).replay(lambda: calls.append("beside"))
    assert calls == ["step", "beside"] * 3 + ["finish"]
    calls.clear()
    StepGraphs(Graph("step"), Graph("finish"), 2).replay()
    assert calls == ["step", "step", "finish"]
    calls.clear()
    WholeRollout(Graph("rollout")).replay(lambda: calls.append("beside"))
    assert calls == ["rollout"]


@pytest.mark.parametrize("normalize_obs", [False, True])
def test_a_rollout_stored_at_a_device_step_index_equals_a_plain_loop_over_the_steps(normalize_obs):
    """The runner's rollout step writes at an index held on the device (so one captured step can replay
    as every step: agents.collect); two rollouts in a row must fill the storage as a loop indexing
    by Python ints does, truncations crossing the rollouts' boundary included."""
    import copy

    cfg = Config(net_dims=(16,), horizon_len=4, minibatch_size=32, seed=2, normalize_obs=normalize_obs)
    env = PointMassVecEnv(8, episode_length=6, seed=3)
    twin = copy.deepcopy(env)
    runner = OnPolicyRunner(env, cfg, print_fn=lambda s: None)
    assert runner.collector.capture == "off"  # on the CPU
    with pytest.raises(ValueError, match="rollout_graph='whole'.*'step', 'rollout', 'off'"):
        OnPolicyRunner(PointMassVecEnv(8), cfg, rollout_graph="whole")
    names = ("raw_obs", "obs", "actions", "log_probs", "values", "means", "rewards", "dones", "truncated", "final_obs")
    raw = None
    for rollout in range(2):
        rng = torch.get_rng_state()
        frozen = copy.deepcopy(runner.normalizer)  # the normaliser learns only after the rollout
        runner.collect()
        torch.set_rng_state(rng)
        if raw is None:
            raw = twin.reset()[0]
            frozen.update(raw, runner.workers)  # the runner's first collect learns the first observations
        steps = {n: [] for n in names}
        with torch.no_grad():
            for t in range(cfg.horizon_len):
                obs = frozen(raw) if normalize_obs else raw
                actions, log_prob, value, mean = runner.policy.act(obs)
                nxt, reward, terminated, truncated, info = twin.step(actions)
                for n, x in zip(names, (raw, obs, actions, log_prob, value, mean, reward, terminated | truncated,
                                        truncated, info["final_obs"])):
                    steps[n].append(x.float().clone())
                raw = nxt.clone()
        for n in names:
            assert torch.equal(getattr(runner.storage, n), torch.stack(steps[n])), (rollout, n)
        assert torch.equal(runner.collector.last_raw_obs, raw) and int(runner.collector.step_index) == 0
        assert runner.storage.truncated.sum() == (0 if rollout == 0 else 8)  # 6-step episodes end in the second


def test_minibatch_size_is_read_under_its_earlier_name_too():
    """Configs and checkpoints saved before the rename wrote ``batch_size``; they load as they were."""
    assert Config.renamed({"batch_size": 8, "gamma": 0.9}) == {"minibatch_size": 8, "gamma": 0.9}
    assert Config.renamed({"batch_size": 8, "minibatch_size": 16}) == {"minibatch_size": 16}
    assert Config.from_preset(PRESETS["Ant"]).replace(batch_size=512).minibatch_size == 512


def test_an_episode_that_ends_on_its_own_at_the_time_limit_is_not_bootstrapped():
    """Gymnasium's TimeLimit reports a termination on the last step as truncated too; the value of what follows
    a termination is 0, so PPO bootstraps only truncated and not terminated (warpgym's info["time_outs"])."""

    class EndsAtTheLimit(PointMassVecEnv):  # the even envs end on their own on the limit's step
        def step(self, actions):
            obs, reward, terminated, truncated, info = super().step(actions)
            return obs, reward, truncated & (torch.arange(self.num_envs) % 2 == 0), truncated, info

    runner = OnPolicyRunner(EndsAtTheLimit(8, episode_length=3), Config(net_dims=(16,), horizon_len=4, minibatch_size=32),
                            print_fn=lambda s: None)
    runner.collect()
    assert runner.storage.dones[2].all()  # every episode ended at the third step
    assert runner.storage.truncated[2].tolist() == [0.0, 1.0] * 4


def test_checkpoint_write_is_atomic_and_round_trips(tmp_path):
    path = str(tmp_path / "ck.pt")
    base = {"iteration": 1, "samples": 2, "policy": {}, "normalizer": {}, "config": {}, "spec": {}}
    save_atomic({**base, "a": torch.arange(3)}, path)
    save_atomic({**base, "a": torch.arange(4)}, path)
    assert os.listdir(tmp_path) == ["ck.pt"]
    assert load(path, torch.device("cpu"))["a"].tolist() == [0, 1, 2, 3]
    with pytest.raises(FileNotFoundError, match="no checkpoint"):
        load(str(tmp_path / "missing.pt"), torch.device("cpu"))


def test_resume_restores_policy_normalizer_optimizer_and_counters(tmp_path):
    cfg = Config(net_dims=(16,), horizon_len=10, minibatch_size=320, repeat_times=2, save_gap=2, eval_gap=1e9)
    a = OnPolicyRunner(PointMassVecEnv(64), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    a.learn(max_iterations=3)
    b = OnPolicyRunner(PointMassVecEnv(64), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    b.load(str(tmp_path / "checkpoint.pt"))
    assert (b.iteration, b.samples) == (3, 3 * 640)
    for pa, pb in zip(a.policy.parameters(), b.policy.parameters()):
        torch.testing.assert_close(pa, pb)
    torch.testing.assert_close(a.normalizer.mean, b.normalizer.mean)
    assert b.ppo.lr.item() == pytest.approx(a.ppo.lr.item())
    b.learn(max_iterations=5)
    assert b.iteration == 5
    rows = [r["iteration"] for r in read_metrics(str(tmp_path))]
    assert rows == [1, 2, 3, 4, 5]


def test_a_policy_plays_with_another_checkpoints_normalizer_and_refuses_what_has_none(tmp_path):
    """``warpgym eval --normalizer-from``: one checkpoint's weights on the inputs another's statistics give."""
    cfg = Config(net_dims=(16,), horizon_len=10, minibatch_size=320, repeat_times=2, save_gap=1, eval_gap=1e9)
    runner = OnPolicyRunner(PointMassVecEnv(64), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    runner.learn(max_iterations=2)
    mine = load(str(tmp_path / "checkpoint.pt"), torch.device("cpu"))
    theirs = {**mine, "normalizer": {**mine["normalizer"], "mean": mine["normalizer"]["mean"] + 0.5}}
    num_obs, num_actions = mine["spec"]["num_obs"], mine["spec"]["num_actions"]
    policy, norm = policy_from_checkpoint(with_normalizer(mine, theirs), num_obs, num_actions, torch.device("cpu"))
    own_policy, own_norm = policy_from_checkpoint(mine, num_obs, num_actions, torch.device("cpu"))
    obs = torch.randn(8, num_obs)
    for a, b in zip(policy.parameters(), own_policy.parameters()):  # the weights stay the checkpoint's own
        torch.testing.assert_close(a, b)
    torch.testing.assert_close(norm.mean, own_norm.mean + 0.5)
    assert not torch.allclose(policy.act_deterministic(norm(obs)), own_policy.act_deterministic(own_norm(obs)))
    plain = {**mine, "config": {**mine["config"], "normalize_obs": False}}
    with pytest.raises(ValueError, match="theirs was trained without an observation normaliser"):
        with_normalizer(mine, plain, ("mine", "theirs"))
    other_task = {**theirs, "spec": {**mine["spec"], "num_obs": num_obs + 1}}
    with pytest.raises(ValueError, match="swap normalisers between checkpoints of one task"):
        with_normalizer(mine, other_task)


def test_agents_imports_nothing_of_the_simulator():
    banned = {"warpgym", "kernels", "warp", "newton", "mujoco_warp", "mujoco"}
    for name in os.listdir(os.path.join(ROOT, "agents")):
        if not name.endswith(".py"):
            continue
        tree = ast.parse(open(os.path.join(ROOT, "agents", name)).read())
        for node in ast.walk(tree):
            mods = [a.name for a in node.names] if isinstance(node, ast.Import) else (
                [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            for m in mods:
                assert m.split(".")[0] not in banned, f"agents/{name} imports {m}"
    code = "import sys, agents, agents.plotting; print(sorted({m.split('.')[0] for m in sys.modules}))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert not banned & set(eval(loaded.stdout))


def test_actor_starts_near_zero_mean_with_the_configured_noise():
    ac = ActorCritic(6, 3, (16, 16), init_noise_std=0.5)
    actions, log_prob, value, mean = ac.act(torch.randn(100, 6))
    assert mean.abs().max() < 0.1 and value.shape == (100,)
    assert actions.std().item() == pytest.approx(0.5, rel=0.2)


def test_rows_logged_one_iteration_late_still_report_their_own_iteration():
    # 8 envs whose 10-step episodes all end together, 4 steps per rollout: episodes finish during
    # iterations 3 (step 10) and 5 (step 20) only
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=10**6)
    runner = OnPolicyRunner(PointMassVecEnv(8, episode_length=10), cfg,
                            eval_env=PointMassVecEnv(4, episode_length=10), print_fn=lambda s: None)
    history = runner.learn(max_iterations=5)
    assert [r["iteration"] for r in history] == [1, 2, 3, 4, 5]
    assert [r["samples"] for r in history] == [32, 64, 96, 128, 160]
    assert [r["episodes"] for r in history] == [0, 0, 8, 0, 8]
    assert [r["length"] for r in history if r["episodes"]] == [10, 10]
    assert all(r["samples_per_s"] > 0 and r["iteration_s"] > 0 for r in history)
    assert ["eval/return" in r for r in history] == [False, False, False, False, True]  # the last row only


def test_an_error_inside_an_iteration_keeps_its_rows_and_the_last_clean_checkpoint(tmp_path):
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=2)
    runner = OnPolicyRunner(PointMassVecEnv(8), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    real_update = runner.update

    def update_then_stop():
        if runner.iteration == 3:
            raise KeyboardInterrupt  # Ctrl-C during the fourth iteration's update
        return real_update()

    runner.update = update_then_stop
    with pytest.raises(KeyboardInterrupt):
        runner.learn(max_iterations=10)
    rows = [r["iteration"] for r in read_metrics(str(tmp_path))]
    assert rows == [1, 2, 3]  # the third was still waiting to be logged when the fourth was cut short
    # the fourth iteration had collected (and moved the normaliser) before it stopped: saving then
    # would mix two iterations, so the checkpoint of iteration 2 stands
    assert load(str(tmp_path / "checkpoint.pt"), torch.device("cpu"))["iteration"] == 2


def test_a_peer_lost_while_gathering_statistics_leaves_no_checkpoint_ahead_of_the_metrics(tmp_path):
    """A peer dies in the collective that gathers iteration 5's statistics: iteration 5 finished,
    but its row was never made. Saving it would leave a resume with no row 5 ever."""
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=2)
    runner = OnPolicyRunner(PointMassVecEnv(8), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    real_sum = runner.workers.sum_

    def sum_or_lose_the_peer(t):
        if runner.iteration == 5:
            raise RuntimeError("Connection closed by peer")  # what gloo raises when the other process dies
        return real_sum(t)

    runner.workers.sum_ = sum_or_lose_the_peer
    with pytest.raises(RuntimeError, match="peer"):
        runner.learn(max_iterations=10)
    assert [r["iteration"] for r in read_metrics(str(tmp_path))] == [1, 2, 3, 4]
    assert load(str(tmp_path / "checkpoint.pt"), torch.device("cpu"))["iteration"] == 4
    resumed = OnPolicyRunner(PointMassVecEnv(8), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    resumed.load(str(tmp_path / "checkpoint.pt"))
    resumed.learn(max_iterations=6)
    assert [r["iteration"] for r in read_metrics(str(tmp_path))] == [1, 2, 3, 4, 5, 6]


def test_checkpoints_are_kept_at_the_first_iteration_after_each_save_at_mark_and_not_again_on_resume(tmp_path):
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=10**6,
                 save_at=(45, 15, 25, 26))
    a = OnPolicyRunner(PointMassVecEnv(8), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    a.elapsed = lambda: 10.0 * a.iteration  # a clock that ticks 10 s per iteration
    a.learn(max_iterations=3)
    assert [(k["marks_s"], k["iteration"]) for k in a.kept] == [([15.0], 2), ([25.0, 26.0], 3)]
    assert load(str(tmp_path / "checkpoint-2.pt"), torch.device("cpu"))["iteration"] == 2
    b = OnPolicyRunner(PointMassVecEnv(8), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    b.load(str(tmp_path / "checkpoint.pt"))  # written at 30 s: the marks before it are the first run's
    b.elapsed = lambda: 10.0 * b.iteration
    b.learn(max_iterations=5)
    # the first run's keeps come with the checkpoint (a resumed run's summary lists the whole run's), none twice
    assert [(k["marks_s"], k["iteration"]) for k in b.kept] == [([15.0], 2), ([25.0, 26.0], 3), ([45.0], 5)]
    assert sorted(f for f in os.listdir(tmp_path) if f.startswith("checkpoint-")) == [
        "checkpoint-2.pt", "checkpoint-3.pt", "checkpoint-5.pt"]


def test_a_stop_request_ends_the_run_after_an_iteration_and_saves_it(tmp_path):
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=10**6)
    runner = OnPolicyRunner(PointMassVecEnv(8), cfg, run_dir=str(tmp_path), print_fn=lambda s: None)
    real_update = runner.update

    def update_and_ask_to_stop():
        if runner.iteration == 3:
            runner.request_stop()  # what a SIGTERM handler does, mid-update
        return real_update()

    runner.update = update_and_ask_to_stop
    history = runner.learn(max_iterations=100)
    # the request is read with iteration 4's statistics, during iteration 5: every process stops there
    assert [r["iteration"] for r in history] == [1, 2, 3, 4, 5]
    assert load(str(tmp_path / "checkpoint.pt"), torch.device("cpu"))["iteration"] == 5


def test_a_time_limit_stops_every_process_after_the_same_iteration():
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=10**6)
    runner = OnPolicyRunner(PointMassVecEnv(8), cfg, print_fn=lambda s: None)
    history = runner.learn(time_limit=0.0)  # over at once: read with iteration 1's row, during iteration 2
    assert [r["iteration"] for r in history] == [1, 2]


@pytest.mark.parametrize("save_gap, end", [(2, "iterations"), (4, "stop read with its own row"),
                                           (5, "stop read the row before"), (2, "time limit")])
def test_the_last_row_carries_the_evaluation_when_the_run_ends_on_a_save(tmp_path, save_gap, end):
    """A save flushes its iteration's row at once (the checkpoint's row first); when that iteration is the run's
    last, the row is the last one, and it carries the run's final evaluation as the row after the loop does.
    Found by a Walker2d-v5 run on an H200 whose time limit was read at iteration 550, a save: no final evaluation."""
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=save_gap)
    runner = OnPolicyRunner(PointMassVecEnv(8), cfg, eval_env=PointMassVecEnv(4, episode_length=10),
                            run_dir=str(tmp_path), print_fn=lambda s: None)
    real_update = runner.update

    def update_and_ask_to_stop():
        if runner.iteration == 3:
            runner.request_stop()  # read with iteration 4's row, the save (4) or during iteration 5, the save (5)
        return real_update()

    if end.startswith("stop"):
        runner.update = update_and_ask_to_stop
    budget = {"iterations": {"max_iterations": 4}, "time limit": {"time_limit": 0.0}}.get(end, {"max_iterations": 100})
    history = runner.learn(**budget)
    last = {"iterations": 4, "time limit": 2}.get(end, save_gap)
    assert [r["iteration"] for r in history] == list(range(1, last + 1))
    assert ["eval/return" in r for r in history] == [False] * (last - 1) + [True]
    assert load(str(tmp_path / "checkpoint.pt"), torch.device("cpu"))["iteration"] == last


class SlowPointMass(PointMassVecEnv):
    """A point mass whose steps take 4 ms of waiting, not of work: its evaluations stay long beside an
    iteration however busy the machine's cores are (a busy machine slowed the iterations of an
    evaluation env that only computed until they were as long as its evaluations)."""

    def step(self, actions):
        time.sleep(0.004)
        return super().step(actions)


def test_evaluation_time_is_left_out_of_the_iteration_it_delays():
    # an evaluation after every row, each far longer than an iteration of 8 envs x 4 steps; the
    # evaluation runs while the next iteration is already queued, so its time belongs to the one after
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=0.0, save_gap=10**6)
    runner = OnPolicyRunner(PointMassVecEnv(8), cfg, eval_env=SlowPointMass(4, episode_length=60),
                            print_fn=lambda s: None)
    history = runner.learn(max_iterations=8)
    assert all("eval_s" in r for r in history)
    steady = history[2:]
    # Medians: one iteration slowed by a busy machine must not fail the test, while an evaluation
    # booked to the wrong row would put its time into every row after the second.
    iteration = statistics.median(r["iteration_s"] for r in steady)
    evaluation = statistics.median(r["eval_s"] for r in steady)
    assert all(r["iteration_s"] > 0 for r in steady) and iteration < 0.5 * evaluation


class FaultyPointMass(PointMassVecEnv):
    """A point mass whose env reports a fault counter (agents.protocol) that rises at step 10."""

    FAULT_HELP = {"glitches": "the test env glitched"}

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.steps = 0
        self.glitches = torch.zeros((), dtype=torch.int64)

    def fault_counters(self):
        return {"glitches": self.glitches}

    def step(self, actions):
        self.steps += 1
        if self.steps >= 10:
            self.glitches += 1
        return super().step(actions)


def test_fault_counters_are_logged_every_row_and_warned_once():
    lines = []
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=10**6)
    runner = OnPolicyRunner(FaultyPointMass(8), cfg, print_fn=lines.append)
    history = runner.learn(max_iterations=5)
    # steps 1-4, 5-8: none; step 9-12: 3 (steps 10, 11, 12); then 4 more per iteration
    assert [r["faults/glitches"] for r in history] == [0, 0, 3, 7, 11]
    warnings = [line for line in lines if line.startswith("warning: glitches")]
    assert len(warnings) == 1 and "= 3 by iteration 3" in warnings[0] and "the test env glitched" in warnings[0]


class CurriculumPointMass(FaultyPointMass):
    """The faulty point mass with a curriculum state (agents.protocol): its steps so far, divided by 4."""

    def curriculum(self):
        return {"stage": torch.tensor(self.steps / 4.0)}


def test_curriculum_state_is_logged_beside_the_faults():
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=1e9, save_gap=10**6)
    history = OnPolicyRunner(CurriculumPointMass(8), cfg, print_fn=lambda s: None).learn(max_iterations=4)
    # read when each iteration's row is staged, after its 4 steps; the fault counter keeps its own column
    assert [r["curriculum/stage"] for r in history] == [1.0, 2.0, 3.0, 4.0]
    assert [r["faults/glitches"] for r in history] == [0, 0, 3, 7]
    flat = OnPolicyRunner(FaultyPointMass(8), cfg, print_fn=lambda s: None).learn(max_iterations=1)
    assert not any(k.startswith("curriculum/") for k in flat[0])
    # the progress line shows it beside the return, and nothing where there is none
    assert "| stage 4.00 |" in progress_line(history[-1], 4) and "stage" not in progress_line(flat[0], 1)


class _Payload:
    """Unpickling this would run code: it records that it ran."""

    def __reduce__(self):
        return (os.makedirs, ("/tmp/warpgym-pickle-ran",))


def test_checkpoints_never_run_code_and_bad_files_name_themselves(tmp_path):
    base = {"iteration": 1, "samples": 2, "policy": {}, "normalizer": {}, "config": {}, "spec": {}}
    evil = tmp_path / "evil.pt"
    torch.save({**base, "rng": _Payload()}, str(evil))
    if os.path.isdir("/tmp/warpgym-pickle-ran"):
        os.rmdir("/tmp/warpgym-pickle-ran")
    with pytest.raises(ValueError, match=r"evil\.pt was not loaded: it holds pickled objects"):
        load(str(evil), torch.device("cpu"))
    assert not os.path.exists("/tmp/warpgym-pickle-ran")  # refused before anything ran

    good = tmp_path / "good.pt"
    save_atomic(base, str(good))
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(ValueError, match=r"truncated\.pt is truncated"):
        load(str(truncated), torch.device("cpu"))
    text = tmp_path / "notes.pt"
    text.write_text("not a checkpoint\n")
    with pytest.raises(ValueError, match=r"notes\.pt is not a warpgym checkpoint"):
        load(str(text), torch.device("cpu"))
    other = tmp_path / "weights.pt"
    torch.save({"weight": torch.zeros(2)}, str(other))
    with pytest.raises(ValueError, match=r"weights\.pt is a torch file but not a warpgym checkpoint"):
        load(str(other), torch.device("cpu"))


def test_a_failed_checkpoint_write_keeps_the_previous_one(tmp_path, monkeypatch):
    path = str(tmp_path / "ck.pt")
    base = {"iteration": 1, "samples": 2, "policy": {}, "normalizer": {}, "config": {}, "spec": {}}
    save_atomic(base, path)

    def disk_full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(torch, "save", disk_full)
    with pytest.raises(OSError, match="the previous checkpoint there is intact"):
        save_atomic({**base, "iteration": 2}, path)
    monkeypatch.undo()
    assert load(path, torch.device("cpu"))["iteration"] == 1
    assert os.listdir(tmp_path) == ["ck.pt"]  # no temporary file left behind


class _TermsEnv:
    """Three envs whose episodes end after 2 and 4 steps and never; each step pays ``reward_alive`` 1 and
    ``reward_step`` its step number, and also reports a position and a per-world matrix that are not terms."""

    num_envs, num_obs, num_actions, max_episode_steps = 3, 1, 1, 6

    def __init__(self):
        self.t = 0

    def reset(self):
        self.t = 0
        return torch.zeros(3, 1), {}

    def step(self, actions):
        self.t += 1
        alive, step = torch.ones(3), torch.full((3,), float(self.t))
        ended = torch.tensor([self.t % 2 == 0, self.t % 4 == 0, False])
        info = {"reward_alive": alive, "reward_step": step, "x_position": torch.full((3,), 9.0),
                "reward_matrix": torch.ones(3, 2)}
        return torch.zeros(3, 1), alive + step, ended, torch.zeros(3, dtype=torch.bool), info


class _Zero:
    def act_deterministic(self, obs):
        return torch.zeros(obs.shape[0], 1)


def test_an_evaluation_logs_each_reward_term_summed_over_the_first_episode_of_every_env():
    from agents.evaluate import evaluate

    result = evaluate(_TermsEnv(), _Zero(), lambda o: o, max_steps=6)
    # episodes of 2, 4 and 6 (cut short) steps; what comes after an env's first episode does not count
    assert result["eval/length"] == pytest.approx(4.0)
    assert result["eval/reward_alive"] == pytest.approx((2 + 4 + 6) / 3)
    assert result["eval/reward_step"] == pytest.approx(((1 + 2) + (1 + 2 + 3 + 4) + 21) / 3)
    assert result["eval/reward_alive"] + result["eval/reward_step"] == pytest.approx(result["eval/return"])
    assert not {"eval/x_position", "eval/reward_matrix"} & set(result)


@pytest.mark.parametrize("woven", [False, True])
def test_a_background_evaluation_scores_the_weights_it_started_with_as_a_synchronous_one_does(woven):
    """agents.background_eval on the CPU: its steps, a chunk per ``advance()`` or one per ``beside()`` (the collector's
    call after each rollout step), give the synchronous evaluation's numbers for the policy and normaliser as they
    were at ``start()``, whatever training does to them meanwhile. After woven steps ``advance()`` queues none."""
    from agents.background_eval import STEPS_PER_ITERATION, BackgroundEvaluation
    from agents.evaluate import evaluate

    torch.manual_seed(3)
    policy = ActorCritic(4, 2, (16,), "elu", 1.0)
    normalizer = RunningMeanStd(4, 5.0)
    normalizer.update(torch.randn(256, 4) * 2.0 + 1.0)
    normalize = normalizer  # the runner's normalize_obs=True path
    max_steps = 2 * STEPS_PER_ITERATION + 5  # the last chunk runs past the episodes' end and counts nothing
    expected = evaluate(PointMassVecEnv(6, episode_length=max_steps, seed=4), policy, normalize, max_steps)

    bg = BackgroundEvaluation(PointMassVecEnv(6, episode_length=max_steps, seed=4), policy, normalizer, True,
                              max_steps, torch.device("cpu"), capturable=False)
    assert not bg.running and bg.poll() is None
    bg.start(policy, normalizer, {"time_s": 12.5, "samples": 640, "iteration": 5})
    with torch.no_grad():  # training moves on: the evaluation keeps the copy it took
        for p in policy.parameters():
            p.add_(0.5)
    normalizer.update(torch.randn(256, 4) * 5.0)
    polls = []
    for _ in range(3):
        assert bg.running
        polls.append(bg.poll())
        if woven:  # a rollout of 32 steps, then the iteration's advance(), which adds nothing
            for _ in range(STEPS_PER_ITERATION):
                bg.beside()
            left = bg.left
            bg.advance()
            assert bg.left == left
        else:
            bg.advance()
    result = bg.poll()
    assert polls == [None, None, None] and not bg.running and bg.poll() is None
    bg.beside()  # nothing under way: nothing queued
    assert bg.left == 0 and not bg.running
    assert result["eval/policy_time_s"] == 12.5 and result["eval/policy_samples"] == 640
    assert set(expected) <= set(result)
    for key, value in expected.items():
        assert result[key] == pytest.approx(value, rel=1e-6, abs=1e-6), key
    assert result["eval/length"] == max_steps  # every episode ran to the time limit, and no further
    # started again, it plays the weights as they are now: another number
    bg.start(policy, normalizer, {"time_s": 30.0, "samples": 1280, "iteration": 10})
    for _ in range(3):
        bg.advance()
    assert bg.poll()["eval/return"] != pytest.approx(expected["eval/return"], rel=1e-3)


def test_a_run_with_background_evaluations_logs_them_on_later_rows_and_ends_with_its_own():
    """``Config.eval_background``: each evaluation's numbers arrive on a row after the one that started it, stamped
    with the policy's time and samples; no row carries an evaluation's time (none stopped the run), but the last,
    whose evaluation is synchronous as without the option."""
    cfg = Config(net_dims=(8,), horizon_len=4, minibatch_size=32, repeat_times=1, eval_gap=0.0, save_gap=10**6,
                 eval_background=True)
    runner = OnPolicyRunner(PointMassVecEnv(8), cfg, eval_env=PointMassVecEnv(4, episode_length=12),
                            print_fn=lambda s: None)
    history = runner.learn(max_iterations=12)
    evaluated = [r for r in history[:-1] if "eval/return" in r]
    assert len(evaluated) == 3 and all("eval_s" not in r for r in history[:-1])
    # its 12 steps go one beside each of the rollouts' 4 (the collector's hook): an evaluation spans 3 iterations,
    # where a chunk of 32 after each iteration would finish one in each
    assert [b["iteration"] - a["iteration"] for a, b in zip(evaluated, evaluated[1:])] == [3, 3]
    assert all(r["eval/length"] == 12 for r in evaluated)
    for r in evaluated:
        assert r["eval/policy_time_s"] <= r["time_s"] and r["eval/policy_samples"] < r["samples"]
        assert r["eval/policy_iteration"] < r["iteration"]
    assert "eval_s" in history[-1] and "eval/policy_time_s" not in history[-1] and "eval/return" in history[-1]
    # an evaluation video draws every step: the evaluations stay synchronous, and the run says so
    said = []
    recorded = OnPolicyRunner(PointMassVecEnv(8), cfg, eval_env=PointMassVecEnv(4, episode_length=40),
                              print_fn=said.append, eval_recorder=object())
    assert recorded.background is None and any("stay synchronous" in line for line in said)
    with pytest.raises(ValueError, match="eval_background='yes' must be True or False"):
        Config(eval_background="yes").validated()


def test_the_curves_add_a_panel_for_a_logged_curriculum_under_the_return(tmp_path):
    """A rough task logs curriculum/terrain_level each row: the run's figures draw it under the return, on the same
    axis of time or samples; a run without one keeps the single panel."""
    import json

    import matplotlib.image

    from agents.plotting import curriculum_keys, plot_runs

    def run(name, curriculum):
        d = tmp_path / name
        d.mkdir()
        rows = [{"iteration": i, "samples": 100 * i, "time_s": float(i), "return": float(i),
                 **({"curriculum/terrain_level": 2.5 - 0.1 * i} if curriculum else {})} for i in range(1, 6)]
        (d / "metrics.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
        return str(d)

    flat, rough = run("flat", False), run("rough", True)
    assert curriculum_keys([[{"return": 1.0, "curriculum/terrain_level": 1.0}], [{"return": 2.0}]]) == \
        ["curriculum/terrain_level"]
    heights = {}
    for name, dirs in (("flat", [flat]), ("both", [flat, rough])):
        paths = plot_runs(dirs, str(tmp_path / f"out_{name}"))
        assert [os.path.basename(p) for p in paths] == ["reward_vs_time.png", "reward_vs_samples.png"]
        heights[name] = matplotlib.image.imread(paths[0]).shape[0]
    assert heights["both"] > 1.3 * heights["flat"]  # 4.5 inches and 6.7: the level's panel is there
