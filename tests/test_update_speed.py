"""Config.compile_update and benchmarks/speed/update_speed.py: the compiled PPO loss learns what the eager one
does, and the benchmark times the learner at the sizes of the real envs."""

from __future__ import annotations

import json

import pytest
import torch

from agents.actor_critic import ActorCritic, gaussian_log_prob
from agents.config import Config
from agents.ppo import PPO, compiled
from agents.storage import RolloutStorage

from benchmarks.speed import update_speed


def learn(compile_update: bool, lagged: bool = False):
    """Three updates of a small policy on a fixed random rollout; the weights and the last statistics."""
    torch.manual_seed(0)
    cfg = Config(net_dims=(32, 16), horizon_len=8, minibatch_size=64, repeat_times=2, compile_update=compile_update)
    policy = ActorCritic(6, 2, cfg.net_dims)
    storage = RolloutStorage(8, 16, 6, 2, torch.device("cpu"))
    g = torch.Generator().manual_seed(1)
    for name in ("obs", "actions", "values", "returns", "advantages"):
        t = getattr(storage, name)
        t.copy_(torch.randn(t.shape, generator=g))
    storage.means.copy_(storage.actions + 0.1 * torch.randn(storage.means.shape, generator=g))
    storage.log_probs.copy_(gaussian_log_prob(storage.actions, storage.means, policy.log_std.detach()))
    # aot_eager: the compiled forward and backward graphs, run by eager kernels (Inductor's C++ build
    # would take half a minute on two cores; by hand it matched within 2e-8)
    ppo = PPO(policy, cfg, torch.device("cpu"), compile_backend="aot_eager")
    torch.manual_seed(2)
    stats = [ppo.update(storage, policy.log_std.detach().clone(), 2, lagged=lagged) for _ in range(3)]
    return policy.state_dict(), stats[-1]


@pytest.mark.parametrize("lagged", [False, True])
def test_the_compiled_loss_learns_the_same_weights_as_the_eager_one(lagged):
    eager, eager_stats = learn(False, lagged)
    comp, comp_stats = learn(True, lagged)
    start = ActorCritic(6, 2, (32, 16)).state_dict()
    moved = max((eager[k] - start[k]).abs().max().item() for k in ("actor.0.weight", "critic.0.weight"))
    assert moved > 1e-3  # the updates changed the weights, so matching them means something
    for name in eager:
        torch.testing.assert_close(comp[name], eager[name], rtol=1e-5, atol=1e-6, msg=name)
    for key in ("loss/surrogate", "loss/value", "policy/kl", "policy/lr", "loss/bounds"):
        torch.testing.assert_close(comp_stats[key], eager_stats[key], rtol=1e-5, atol=1e-7, msg=key)


def test_compile_update_is_a_config_switch_the_command_line_sets():
    from warpgym.cli import run_setup, train

    with pytest.raises(ValueError, match="compile_update='yes' must be True or False"):
        Config(compile_update="yes").validated()
    cfg = run_setup.build_config(train.parse_args(["--task", "Ant", "--compile-update"]), "Ant", 64, "cpu")
    assert cfg.compile_update is True
    assert run_setup.build_config(train.parse_args(["--task", "Ant"]), "Ant", 64, "cpu").compile_update is False


def test_compiling_on_a_gpu_without_triton_says_how_to_go_on():
    try:
        import triton  # noqa: F401
    except ImportError:
        pass
    else:
        pytest.skip("Triton is installed here")
    with pytest.raises(RuntimeError, match="needs Triton.*without --compile-update"):
        compiled(lambda x: x, torch.device("cuda"), "inductor")


def test_the_benchmark_uses_the_envs_observation_and_action_sizes(ant_env, humanoid_env):
    for task, env in (("Ant", ant_env), ("Humanoid", humanoid_env)):
        assert update_speed.SIZES[task] == (env.num_obs, env.num_actions), task


def test_the_benchmark_times_each_mode_against_the_graph_mode(tmp_path, capsys):
    code = update_speed.main(["--out", str(tmp_path), "--tasks", "Ant", "--envs", "16", "--batch-size", "128",
                              "--device", "cpu", "--repeats", "2", "--warmup", "0", "--modes", "graph", "eager"])
    assert code == 0
    doc = json.loads((tmp_path / "update_speed.json").read_text())
    graph, eager = doc["rows"]
    assert (graph["mode"], eager["mode"]) == ("graph", "eager")
    assert graph["minibatch_steps"] == 4 * 2  # 16 envs x 16 steps / 128, four passes (the Ant's preset)
    assert len(graph["update_ms_all"]) == 2 and graph["update_ms_median"] > 0
    table = capsys.readouterr().out
    assert "| Ant | 16 | graph | 8 |" in table and "| 1.00 |" in table
    ratio = eager["update_ms_median"] / graph["update_ms_median"]
    assert f"| {ratio:.2f} |" in table


def test_the_benchmark_names_a_size_the_mini_batch_does_not_divide(tmp_path, capsys):
    with pytest.raises(SystemExit):
        update_speed.main(["--out", str(tmp_path), "--tasks", "Ant", "--envs", "3", "--batch-size", "5",
                           "--device", "cpu", "--modes", "eager"])
    assert "--envs 3 for Ant" in capsys.readouterr().err
