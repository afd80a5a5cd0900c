"""A damaged file gets one clear line, never a traceback: truncated, empty, flipped or foreign
checkpoints given to the library's load, play.py, sim2sim.py and train.py --resume, and a damaged
config.json. Every truncation and byte flip of a real checkpoint either loads as written or is refused
by name; nothing loaded runs code."""

import io
import json
import os
import shutil
import subprocess
import sys

import pytest
import torch
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from agents.checkpoint import load_bytes, save_atomic

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
POLICY = os.path.join(ROOT, "tests", "data", "ant_armature_policy.pt")
WHAT = ("is truncated", "is damaged", "is empty", "is not a warpgym checkpoint", "was not loaded")


@pytest.fixture(scope="module")
def sealed(tmp_path_factory):
    """A checkpoint as train.py writes one today (sealed), its bytes and its content."""
    content = torch.load(POLICY, map_location="cpu", weights_only=True)
    path = str(tmp_path_factory.mktemp("ckpt") / "checkpoint.pt")
    save_atomic(content, path)
    with open(path, "rb") as f:
        return path, f.read(), content


def loads_as_written(data: bytes, content: dict) -> bool:
    ckpt = load_bytes(data, "run/checkpoint.pt", torch.device("cpu"))
    return (ckpt["config"] == content["config"] and ckpt["iteration"] == content["iteration"]
            and all(torch.equal(ckpt["policy"][k], v) for k, v in content["policy"].items())
            and all(torch.equal(ckpt["normalizer"][k], v) for k, v in content["normalizer"].items()))


def refused_by_name(error: ValueError) -> bool:
    text = str(error)
    return text.startswith("run/checkpoint.pt ") and any(w in text for w in WHAT) and "earlier checkpoint" in text


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cut=st.floats(0.0, 1.0, exclude_max=True), flip=st.floats(0.0, 1.0, exclude_max=True),
       bit=st.integers(0, 7), truncate=st.booleans())
def test_every_truncation_or_flipped_bit_loads_as_written_or_is_refused_by_name(sealed, cut, flip, bit, truncate):
    _, data, content = sealed
    if truncate:
        damaged = data[: int(cut * len(data))]
    else:
        b = bytearray(data)
        b[int(flip * len(b))] ^= 1 << bit
        damaged = bytes(b)
    try:
        assert loads_as_written(damaged, content)
    except ValueError as e:
        assert refused_by_name(e), str(e)


def test_a_changed_tensor_value_is_caught_by_the_seal(sealed):
    """torch.load alone reads a flipped bit inside a tensor back without complaint."""
    _, data, content = sealed
    raw = bytearray(data)
    weights = content["policy"]["actor.0.weight"].numpy().tobytes()
    at = bytes(raw).find(weights[:64])
    assert at > 0
    raw[at + 10] ^= 0x10
    assert torch.load(io.BytesIO(bytes(raw)), weights_only=True)["iteration"] == content["iteration"]  # unnoticed
    with pytest.raises(ValueError, match="its bytes changed after it was written"):
        load_bytes(bytes(raw), "run/checkpoint.pt", torch.device("cpu"))


def one_line(proc: subprocess.CompletedProcess) -> str:
    """The process's complaint: it failed, with no traceback, on one line (Warp's no-GPU notice aside)."""
    lines = [ln for ln in proc.stderr.splitlines() if ln.strip() and not ln.startswith("Warp CUDA warning")]
    assert proc.returncode != 0 and "Traceback" not in proc.stderr, proc.stderr[-2000:]
    assert len(lines) == 1, proc.stderr[-2000:]
    return lines[0]


def script(name: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, os.path.join(ROOT, "scripts", name), *args], capture_output=True,
                          text=True, timeout=120, cwd=ROOT)


@pytest.fixture(scope="module")
def damaged_files(sealed, tmp_path_factory):
    path, data, _ = sealed
    d = tmp_path_factory.mktemp("damaged")
    files = {"truncated": data[:5000], "empty": b"", "foreign": b'{"not": "a checkpoint"}\n'}
    out = {}
    for name, content in files.items():
        out[name] = str(d / f"{name}.pt")
        with open(out[name], "wb") as f:
            f.write(content)
    return out


@pytest.mark.parametrize("kind, says", [("truncated", "is truncated"), ("empty", "is empty"),
                                        ("foreign", "is not a warpgym checkpoint")])
@pytest.mark.parametrize("command", ["play.py", "sim2sim.py"])
def test_play_and_sim2sim_answer_a_damaged_checkpoint_with_one_line(damaged_files, command, kind, says):
    line = one_line(script(command, damaged_files[kind], "--device", "cpu"))
    assert damaged_files[kind] in line and says in line and "--keep-checkpoints" in line, line


def test_play_answers_a_wrong_path_with_one_line(tmp_path):
    line = one_line(script("play.py", str(tmp_path / "nowhere"), "--device", "cpu"))
    assert "no checkpoint at" in line and "nowhere" in line


def run_dir_with(tmp_path, checkpoint: bytes | None, config: bytes) -> str:
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.json").write_bytes(config)
    if checkpoint is not None:
        (run / "checkpoint.pt").write_bytes(checkpoint)
    return str(run)


GOOD_CONFIG = json.dumps({"task": "Ant", "device": "cpu", "num_envs": 4, "seed": 0,
                          "env_args": {"task": "Ant", "num_envs": 4}}).encode()


@pytest.mark.parametrize("kind, says", [("truncated", "is truncated"), ("empty", "is empty")])
def test_resume_answers_a_damaged_checkpoint_with_one_line(sealed, tmp_path, kind, says):
    data = {"truncated": sealed[1][:5000], "empty": b""}[kind]
    run = run_dir_with(tmp_path, data, GOOD_CONFIG)
    line = one_line(script("train.py", "--resume", run))
    assert f"--resume {run}" in line and says in line and "--keep-checkpoints" in line, line


@pytest.mark.parametrize("config, says", [(GOOD_CONFIG[:40], "not valid JSON"), (b"", "empty"),
                                          (b'{"task": "Ant"}', "is not a warpgym run's config")])
def test_resume_answers_a_damaged_config_with_one_line(sealed, tmp_path, config, says):
    run = run_dir_with(tmp_path, sealed[1], config)
    line = one_line(script("train.py", "--resume", run))
    assert os.path.join(run, "config.json") in line and says in line, line


def test_a_sealed_checkpoint_still_plays(sealed, tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    shutil.copy(sealed[0], run / "checkpoint.pt")
    done = script("play.py", str(run), "--device", "cpu", "--num-envs", "1", "--steps", "5", "--json",
                  str(tmp_path / "play.json"))
    assert done.returncode == 0, done.stderr[-2000:]
    assert json.loads((tmp_path / "play.json").read_text())["eval/length"] == 5
