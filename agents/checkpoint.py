"""Checkpoints written atomically (a crash mid-write leaves the previous file intact)."""

from __future__ import annotations

import os

import torch


def save_atomic(obj: dict, path: str) -> None:
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    tmp = f"{path}.tmp{os.getpid()}"
    with open(tmp, "wb") as f:
        torch.save(obj, f)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def load(path: str, device: torch.device) -> dict:
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no checkpoint at {path}: pass a file written by scripts/train.py")
    return torch.load(path, map_location=device, weights_only=False)


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
