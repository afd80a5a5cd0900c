"""Checks that need a GPU: they run on the CUDA machine (`pytest tests/test_cuda.py`) and skip in CI."""

import copy
import os
import subprocess
import sys

import pytest
import torch

import reference

pytestmark = pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA GPU")
DEV = "cuda:0"


def filled_storage(num_envs=256, horizon=8, obs=12, act=3, seed=0):
    from agents.storage import RolloutStorage

    g = torch.Generator(device=DEV).manual_seed(seed)
    s = RolloutStorage(horizon, num_envs, obs, act, torch.device(DEV))
    for t in (s.obs, s.actions, s.means, s.values, s.returns, s.advantages):
        t.copy_(torch.randn(t.shape, generator=g, device=DEV))
    s.log_probs.copy_(-torch.rand(s.log_probs.shape, generator=g, device=DEV) * 3)
    return s


def test_graph_captured_update_matches_the_eager_one():
    from agents import Config
    from agents.actor_critic import ActorCritic
    from agents.ppo import PPO

    cfg = Config(net_dims=(32, 32), horizon_len=8, minibatch_size=512, repeat_times=3).validated()
    torch.manual_seed(0)
    base = ActorCritic(12, 3, cfg.net_dims).to(DEV)
    results = []
    for graph in (False, True):
        policy = copy.deepcopy(base)
        ppo = PPO(policy, cfg, torch.device(DEV), cuda_graph=graph)
        storage = filled_storage(seed=0)
        for it in range(3):  # the graph is captured during the first update and replayed after
            fresh = filled_storage(seed=it)  # a new rollout, written into the same buffers
            for name in ("obs", "actions", "means", "values", "returns", "advantages", "log_probs"):
                getattr(storage, name).copy_(getattr(fresh, name))
            torch.manual_seed(100 + it)
            stats = ppo.update(storage, policy.log_std.detach().clone(), 4)
        results.append((torch.cat([p.detach().flatten() for p in policy.parameters()]), stats))
    (p_eager, s_eager), (p_graph, s_graph) = results
    torch.testing.assert_close(p_graph, p_eager, atol=1e-5, rtol=1e-4)
    for key in s_eager:
        torch.testing.assert_close(s_graph[key], s_eager[key], atol=1e-5, rtol=1e-4)


@pytest.mark.skipif(torch.cuda.device_count() < 2, reason="needs 2 GPUs")
def test_captured_update_with_nccl_in_the_graph_matches_the_eager_one_on_two_gpus(tmp_path):
    """Two processes, one GPU each: the mini-batch step replayed from a CUDA graph that holds the
    gradient/KL all-reduce gives the eager step's policy, and both ranks hold the same policy."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    cmd = [sys.executable, "-m", "torch.distributed.run", "--standalone", "--nproc_per_node=2",
           "tests/dist_update_worker.py", str(tmp_path)]
    done = subprocess.run(cmd, cwd=root, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    r0, r1 = (torch.load(tmp_path / f"rank{r}.pt", weights_only=True) for r in (0, 1))
    assert r0["graph"]["captured"] and r1["graph"]["captured"] and not r0["eager"]["captured"]
    for r in (r0, r1):
        torch.testing.assert_close(r["graph"]["params"], r["eager"]["params"], atol=1e-5, rtol=1e-4)
        for key in r["eager"]["stats"]:
            torch.testing.assert_close(r["graph"]["stats"][key], r["eager"]["stats"][key], atol=1e-5, rtol=1e-4)
    # the all-reduce ran inside every replay: one policy, though each rank trained on its own data
    # (a graph without the collective would leave each rank with its own)
    assert torch.equal(r0["graph"]["params"], r1["graph"]["params"])
    assert torch.equal(r0["eager"]["params"], r1["eager"]["params"])
    assert not torch.equal(r0["graph"]["stats"]["loss/value"], r1["graph"]["stats"]["loss/value"])


@pytest.mark.parametrize("task", ["Ant", "Hopper-v5"])
def test_captured_rollout_matches_the_eager_one(task):
    """Rollouts replayed from CUDA graphs (policy, env step with its Warp launches, storage, GAE), one
    step's graph replayed horizon_len times or the whole rollout's, give what the same rollouts launched
    step by step give: same seeds, same numbers. Newton's Ant and a suite task (MuJoCo Warp's step,
    Gymnasium's observation and reward)."""
    from agents import Config, OnPolicyRunner
    from warpgym.tasks.presets import PRESETS
    from warpgym.envs import make_vec_env

    cfg = Config.from_preset(PRESETS[task], horizon_len=8, minibatch_size=256)
    names = ("raw_obs", "actions", "rewards", "dones", "truncated", "final_obs", "advantages", "returns")
    runs = []
    for graph in ("off", "step", "rollout"):
        # 12-step episodes, so truncations (and their bootstrap from final_obs) happen inside the graph
        env = make_vec_env(task, num_envs=32, device=DEV, seed=5, max_episode_steps=12)
        runner = OnPolicyRunner(env, cfg, print_fn=lambda s: None, rollout_graph=graph)
        rollouts = []
        for _ in range(4):  # eager; captured and replayed; replayed; replayed
            runner.collect()
            rollouts.append({n: getattr(runner.storage, n).clone() for n in names}
                            | {"norm_mean": runner.normalizer.mean.clone()})
        assert (runner.collector.graph is not None) == (graph != "off")
        runs.append((rollouts, runner.episodes.read_and_clear()))
    (eager, eager_eps) = runs[0]
    for captured, captured_eps in runs[1:]:
        assert eager_eps["episodes"] == captured_eps["episodes"] > 0
        assert sum(int(r["truncated"].sum()) for r in captured[1:]) > 0  # the graph bootstrapped truncations
        _assert_rollouts_close(eager, captured)


@pytest.mark.parametrize("woven", [False, True])
def test_background_evaluation_replayed_on_its_side_stream_matches_a_synchronous_one(woven):
    """agents.background_eval on a GPU: after one eager chunk the evaluation's step (policy copy, MuJoCo Warp's
    step, tally) replays as a one-step CUDA graph on a side stream, a chunk per ``advance()`` or one step per
    ``beside()`` between the main stream's work, while the main stream changes the policy and works; the result is
    the synchronous evaluation's of the weights at the start, read without a wait."""
    from agents import Config, OnPolicyRunner
    from warpgym.tasks.presets import PRESETS
    from agents.background_eval import BackgroundEvaluation
    from agents.evaluate import evaluate
    from warpgym.envs import make_vec_env

    cfg = Config.from_preset(PRESETS["Hopper-v5"], horizon_len=8, minibatch_size=256)
    runner = OnPolicyRunner(make_vec_env("Hopper-v5", num_envs=32, device=DEV, seed=1), cfg, print_fn=lambda s: None)
    runner.collect()  # a normaliser with statistics
    policy, normalizer = runner.policy, runner.normalizer

    def eval_env():  # short episodes: the runs end (falls and time limits) inside the captured steps
        return make_vec_env("Hopper-v5", num_envs=16, device=DEV, seed=5, max_episode_steps=150)

    with torch.no_grad():
        expected = evaluate(eval_env(), policy, normalizer, 150)
    bg = BackgroundEvaluation(eval_env(), policy, normalizer, True, 150, torch.device(DEV), capturable=True)
    bg.start(policy, normalizer, {"time_s": 1.0, "samples": 2, "iteration": 3})
    busy = torch.randn(2048, 2048, device=DEV)
    results = []
    while not results:
        wove = woven and bg.graph is not None
        for _ in range(8 if wove else 0):  # a rollout's steps, each with one of its own
            bg.beside()
            with torch.no_grad():
                busy = (busy @ busy).tanh_()
        left = bg.left
        bg.advance()
        assert not wove or bg.left == left  # woven steps: the iteration's advance() queues none of its own
        with torch.no_grad():  # training goes on on the main stream
            for p in policy.parameters():
                p.mul_(0.9)
            busy = (busy @ busy).tanh_()
        r = bg.poll()
        if r is not None:
            results.append(r)
        elif bg.left == 0:
            torch.cuda.synchronize()
    assert bg.graph is not None
    for key, value in expected.items():
        assert results[0][key] == pytest.approx(value, rel=2e-2, abs=0.5), key


def _assert_rollouts_close(eager, captured):
    for i, (a, b) in enumerate(zip(eager, captured)):
        for name in a:
            # MuJoCo Warp's float atomics differ run to run by ~1e-4 m after a few dozen steps; the
            # reward's progress term divides a position change by dt (1/60 s), so it differs by up to
            # ~1e-2 (seen: 3.9e-3 in 2 of 256 entries on an H100). A rollout that read a stale buffer
            # or skipped a launch would be off by far more.
            atol = 2e-2 if name == "rewards" else 1e-3
            torch.testing.assert_close(b[name], a[name], atol=atol, rtol=1e-3, msg=lambda m: f"rollout {i} {name}: {m}")


def test_env_on_cuda_matches_the_torch_reference_from_another_stream():
    from warpgym.envs import LocomotionVecEnv

    env = LocomotionVecEnv("Ant", num_envs=64, device=DEV, seed=0)
    env.reset(seed=1)
    stream = torch.cuda.Stream()
    with torch.cuda.stream(stream):  # the env orders itself after whatever stream torch is on
        for _ in range(20):
            before = reference.potentials(env.sim.acquire_actor_root_state_tensor().cpu(), env.task)
            actions = torch.rand(64, 8, device=DEV) * 2 - 1
            obs, rew, term, trunc, _ = env.step(actions)
            live = (~(term | trunc)).cpu()
            ref_obs = reference.observation(_CpuView(env.sim), env.task, actions.cpu())
            progress = reference.potentials(env.sim.acquire_actor_root_state_tensor().cpu(), env.task) - before
            ref_rew = reference.reward(ref_obs, actions.cpu(), progress, env.task, env.sim.motor_gear_np)
            torch.testing.assert_close(obs.cpu()[live], ref_obs[live], atol=5e-4, rtol=1e-3)
            torch.testing.assert_close(rew.cpu()[live], ref_rew[live], atol=5e-3, rtol=1e-3)


class _CpuView:
    """Hands the reference CPU copies of the CUDA sim's Tensor API buffers."""

    def __init__(self, sim):
        self._sim = sim

    def __getattr__(self, name):
        attr = getattr(self._sim, name)
        if name.startswith("acquire_"):
            return lambda: attr().cpu()
        return attr
