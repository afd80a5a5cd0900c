"""Checkpoints: written atomically (a crash mid-write leaves the previous file intact) and read
without running code (``weights_only``: tensors and plain values only, never pickled objects)."""

from __future__ import annotations

import glob
import io
import os
import pickle
import zipfile

import torch

REQUIRED = ("iteration", "samples", "policy", "normalizer", "config", "spec")


def save_atomic(obj: dict, path: str) -> None:
    """Write ``obj`` to ``path`` whole or not at all: a temporary file, flushed to disk, then renamed.

    If the write fails (a full disk, say), the previous checkpoint is left as it was and the error
    says so."""
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = f"{path}.tmp{os.getpid()}"
    for stale in glob.glob(glob.escape(path) + ".tmp*"):  # a process killed mid-write left it
        if stale != tmp:
            try:
                os.remove(stale)
            except OSError:
                pass
    try:
        with open(tmp, "wb") as f:
            torch.save(obj, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        try:
            os.remove(tmp)
        except OSError:
            pass
        kept = "the previous checkpoint there is intact" if os.path.exists(path) else "no checkpoint was written"
        raise OSError(e.errno, f"could not write checkpoint {path} ({e.strerror or e}); {kept}: "
                               "free disk space or pick another --run-dir, then --resume") from e


def read_checkpoint_bytes(path: str) -> bytes:
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no checkpoint at {path}: pass a file written by scripts/train.py")
    with open(path, "rb") as f:
        return f.read()


def load_bytes(data: bytes, path: str, device: torch.device) -> dict:
    """A checkpoint from its bytes (``path`` names it in errors). Refuses anything that is not a
    torch file of tensors and plain values with a warpgym checkpoint's keys, and runs no code."""
    if not data.startswith(b"PK\x03\x04"):  # torch.save writes a zip archive
        raise ValueError(f"{path} is not a readable torch checkpoint (not a zip archive as torch.save writes; "
                         "another kind of file, or empty); use a checkpoint written by scripts/train.py")
    try:
        ckpt = torch.load(io.BytesIO(data), map_location=device, weights_only=True)
    except pickle.UnpicklingError as e:
        raise ValueError(f"{path} holds pickled objects other than tensors and plain values, which may run code "
                         f"when loaded; it was not loaded ({str(e).splitlines()[0][:200]}). Use a checkpoint "
                         "written by scripts/train.py, from a source you trust") from e
    except (RuntimeError, EOFError, zipfile.BadZipFile, OSError) as e:
        raise ValueError(f"{path} is not a readable torch checkpoint (truncated, or another kind of file: "
                         f"{type(e).__name__}: {str(e).splitlines()[0][:200]}); use a checkpoint written by "
                         "scripts/train.py") from e
    if not isinstance(ckpt, dict) or any(k not in ckpt for k in REQUIRED):
        have = sorted(ckpt) if isinstance(ckpt, dict) else type(ckpt).__name__
        raise ValueError(f"{path} is a torch file but not a warpgym checkpoint (it has {have}, a checkpoint has "
                         f"{list(REQUIRED)}); use a checkpoint written by scripts/train.py")
    return ckpt


def load(path: str, device: torch.device) -> dict:
    return load_bytes(read_checkpoint_bytes(path), path, device)


def rng_state(device: torch.device) -> dict:
    state = {"torch": torch.get_rng_state()}
    if device.type == "cuda":
        state["cuda"] = torch.cuda.get_rng_state(device)
    return state


def set_rng_state(state: dict, device: torch.device) -> None:
    torch.set_rng_state(state["torch"].cpu())
    if device.type == "cuda" and "cuda" in state:
        torch.cuda.set_rng_state(state["cuda"].cpu(), device)


def policy_from_checkpoint(ckpt: dict, num_obs: int, num_actions: int, device: torch.device):
    """The trained actor-critic and its observation normaliser, ready for evaluation."""
    from agents.actor_critic import ActorCritic  # noqa: PLC0415
    from agents.normalizer import RunningMeanStd  # noqa: PLC0415

    cfg = ckpt["config"]
    have = (ckpt["spec"]["num_obs"], ckpt["spec"]["num_actions"])
    if have != (num_obs, num_actions):
        raise ValueError(f"checkpoint is for obs/action sizes {have}, the env has {(num_obs, num_actions)}")
    policy = ActorCritic(num_obs, num_actions, tuple(cfg["net_dims"]), cfg["activation"]).to(device)
    policy.load_state_dict(ckpt["policy"])
    if not cfg["normalize_obs"]:
        return policy, lambda obs: obs
    norm = RunningMeanStd(num_obs, cfg["obs_clip"]).to(device)
    norm.load_state_dict(ckpt["normalizer"])
    return policy, norm
