"""warpgym export: the ONNX and torch.export files act as the checkpoint's policy, and policy.json's contract (the
observation's terms, the joints, their targets) is the layout warpgym's env observes and acts by."""

import json
import os
import sys

import numpy as np
import pytest
import torch

from agents.checkpoint import load, policy_from_checkpoint, save_atomic
from warpgym.cli import export

TASK = "Go1VelocityFlat-v0"


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """A run directory holding a checkpoint of the Go1's shape as the runner saves it: random weights and a
    normaliser whose statistics are far from zero mean and unit variance (so the export's normaliser matters)."""
    from agents import Config
    from warpgym.tasks.presets import PRESETS
    from agents.actor_critic import ActorCritic
    from agents.normalizer import RunningMeanStd

    torch.manual_seed(0)
    cfg = Config.from_preset(PRESETS[TASK], env_args={"task": TASK})
    policy = ActorCritic(48, 12, cfg.net_dims, cfg.activation, num_critic_obs=72)
    norm = RunningMeanStd(48, cfg.obs_clip)
    norm.update(torch.randn(512, 48) * torch.linspace(0.1, 4.0, 48) + torch.linspace(-2.0, 2.0, 48))
    d = tmp_path_factory.mktemp("export") / "go1"
    d.mkdir()
    save_atomic({"iteration": 7, "samples": 7 * 4096 * 24, "policy": policy.state_dict(),
                 "normalizer": norm.state_dict(), "config": cfg.to_dict(),
                 "spec": {"num_obs": 48, "num_actions": 12, "num_critic_obs": 72}}, str(d / "checkpoint.pt"))
    return str(d)


def checkpoint_actions(ckpt, obs):
    spec = ckpt["spec"]
    policy, normalize = policy_from_checkpoint(ckpt, spec["num_obs"], spec["num_actions"], torch.device("cpu"))
    with torch.no_grad():
        return policy.act_deterministic(normalize(obs))


def test_both_files_act_as_the_checkpoints_policy_at_any_batch_size(run, tmp_path, capsys):
    from onnx.reference import ReferenceEvaluator

    out = str(tmp_path / "out")
    assert export.main([run, "--out", out]) == 0
    assert "48 observations in, 12 actions out" in capsys.readouterr().out
    ckpt = load(os.path.join(run, "checkpoint.pt"), torch.device("cpu"))
    assert float(ckpt["normalizer"]["var"].sub(1).abs().max()) > 0.1  # a normaliser that matters
    scripted = torch.export.load(os.path.join(out, "policy.pt2")).module()
    onnx_model = ReferenceEvaluator(os.path.join(out, "policy.onnx"))
    gen = torch.Generator().manual_seed(0)
    for batch in (1, 64):
        obs = 3 * torch.randn(batch, 48, generator=gen)  # some inputs beyond the normaliser's clip
        want = checkpoint_actions(ckpt, obs)
        assert torch.allclose(scripted(obs), want, atol=1e-6)
        (got,) = onnx_model.run(None, {"obs": obs.numpy()})
        assert got.shape == (batch, 12) and np.allclose(got, want.numpy(), atol=1e-5)


def test_a_policy_without_a_normaliser_is_the_bare_actor(run, tmp_path):
    ckpt = load(os.path.join(run, "checkpoint.pt"), torch.device("cpu"))
    ckpt["config"] = {**ckpt["config"], "normalize_obs": False}
    path = str(tmp_path / "bare.pt")
    save_atomic(ckpt, path)
    assert export.main([path, "--out", str(tmp_path / "bare"), "--no-onnx"]) == 0
    obs = torch.randn(5, 48, generator=torch.Generator().manual_seed(1)) * 50  # no clip applies
    scripted = torch.export.load(str(tmp_path / "bare" / "policy.pt2")).module()
    assert torch.allclose(scripted(obs), checkpoint_actions(ckpt, obs), atol=1e-5)
    contract = json.loads((tmp_path / "bare" / "policy.json").read_text())
    assert contract["normalizer"] is False and contract["files"] == {"torch_export": "policy.pt2"}


def test_the_contract_is_the_layout_the_env_observes_and_acts_by(run, tmp_path):
    """Write a state whose joints sit off their defaults, step with a known action: the env's observation holds the
    joints' offsets, the action and the command where policy.json says, and its position targets are
    default_joint_pos + scale * action."""
    from warpgym.envs.legged import LeggedVecEnv

    out = tmp_path / "c"
    assert export.main([run, "--out", str(out), "--no-onnx"]) == 0
    contract = json.loads((out / "policy.json").read_text())
    terms = {t["name"]: t["size"] for t in contract["observation"]}
    starts = dict(zip(terms, np.cumsum([0, *terms.values()])))
    assert sum(terms.values()) == contract["num_obs"] == 48 and contract["control_dt"] == pytest.approx(0.02)
    act = contract["action"]
    assert len(act["joints"]) == len(act["default_joint_pos"]) == len(act["stiffness"]) == contract["num_actions"]

    env = LeggedVecEnv(TASK, num_envs=2, device="cpu", seed=0, observation_noise=False, events={"push_robot": None})
    env.reset(seed=0)
    action = torch.linspace(-0.5, 0.5, 12).repeat(2, 1)
    obs, *_ = env.step(action)
    state = env.state()
    j = env.index.joint_qpos
    joint_pos = state["qpos"][:, j] - torch.as_tensor(act["default_joint_pos"])
    sl = lambda name: slice(starts[name], starts[name] + terms[name])  # noqa: E731
    # as the world's encoder reads it: its randomised bias added (mjlab's encoder_bias event)
    assert torch.allclose(obs[:, sl("joint_pos")], joint_pos + state["encoder_bias"], atol=1e-5)
    assert float(joint_pos.abs().max()) > 1e-3  # off the defaults, so the slice is checked against something
    assert torch.allclose(obs[:, sl("actions")], action, atol=1e-6)
    assert torch.allclose(obs[:, sl("command")], state["command"], atol=1e-6)
    ctrl = env.sim.to_torch(env.sim.d.ctrl)[:, env.index.joint_actuator]
    target = torch.as_tensor(act["default_joint_pos"]) + torch.as_tensor(act["scale"]) * action
    # the target is in the encoder's reading, as the policy sees the joints: the world's actuator gets it less the bias
    assert torch.allclose(ctrl + state["encoder_bias"], target, atol=1e-5)


def test_the_observations_of_every_legged_task_add_up_to_mjlabs_widths():
    from warpgym.tasks.legged import get_legged_task
    from warpgym.tasks.legged.model import compile_task_scene, policy_terms, resolve

    # mjlab 1.6's actor observations (its env's observation_manager, built in CI's mjlab environment)
    widths = {"Go1VelocityFlat-v0": 48, "G1VelocityFlat-v0": 99, "Go1VelocityRough-v0": 235, "G1VelocityRough-v0": 286}
    for name, width in widths.items():
        task = get_legged_task(name)
        idx = resolve(task, compile_task_scene(task)[0].mjm)
        terms = policy_terms(task, idx, len(idx.joint_actuator))
        assert sum(size for _, size, _ in terms) == width, name
        assert [n for n, _, _ in terms][-1] == ("height_scan" if "Rough" in name else "command")


def test_bad_input_is_one_line_and_a_failed_write_keeps_the_previous_file(run, tmp_path, capsys, monkeypatch):
    out = tmp_path / "keep"
    assert export.main([run, "--out", str(out)]) == 0
    before = (out / "policy.onnx").read_bytes()
    monkeypatch.setitem(sys.modules, "onnx", None)  # not installed
    with pytest.raises(SystemExit) as e:
        export.main([run, "--out", str(out)])
    assert e.value.code == 2 and 'pip install "warpgym[export]"' in capsys.readouterr().err
    monkeypatch.undo()

    def fail(*a, **k):
        raise RuntimeError("disk full")

    monkeypatch.setattr(torch.onnx, "export", fail)
    with pytest.raises(RuntimeError, match="disk full"):
        export.main([run, "--out", str(out)])
    assert (out / "policy.onnx").read_bytes() == before and not (out / "policy.tmp.onnx").exists()
    with pytest.raises(SystemExit, match="no checkpoint at .*nothing"):
        export.main([str(tmp_path / "nothing"), "--out", str(out)])
