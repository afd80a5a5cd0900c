"""Checkpoints: written atomically (a crash mid-write leaves the previous file intact), sealed with a
checksum of their bytes, and read without running code (``weights_only``: tensors and plain values
only, never pickled objects).

The seal is a SHA-256 of the archive in the zip comment that ends the file, where torch.load does not
look: torch reads a changed byte in a tensor back without complaint, the seal does not. A file
written before checkpoints were sealed loads unchecked."""

from __future__ import annotations

import glob
import hashlib
import io
import os
import pickle
import struct

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
        with open(tmp, "w+b") as f:
            torch.save(obj, f)
            _seal(f)
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


SEAL = b"warpgym-sha256:"
_END = b"PK\x05\x06"  # a zip archive's last record: 20 bytes of fields, the comment's length, the comment


def _seal(f) -> None:
    """Put a SHA-256 of everything before the comment into the archive's comment."""
    f.flush()
    f.seek(0)
    data = f.read()
    end = data.rfind(_END)
    if end < 0 or len(data) - end != 22:  # torch.save writes an archive without a comment
        raise ValueError("torch.save wrote an archive with a comment; warpgym cannot seal it")
    comment = SEAL + hashlib.sha256(data[: end + 20]).hexdigest().encode()
    f.seek(end + 20)
    f.write(struct.pack("<H", len(comment)) + comment)
    f.truncate()


def _check_seal(data: bytes, end: int, path: str) -> None:
    comment = data[end + 22 :]
    if not comment.startswith(SEAL):
        return  # written before checkpoints were sealed
    if hashlib.sha256(data[: end + 20]).hexdigest().encode() != comment[len(SEAL) :]:
        raise ValueError(f"{path} is damaged: its bytes changed after it was written (its checksum does not "
                         f"match); {EARLIER}")


def read_checkpoint_bytes(path: str) -> bytes:
    if not os.path.isfile(path):
        raise FileNotFoundError(f"no checkpoint at {path}: pass a file written by warpgym train")
    with open(path, "rb") as f:
        return f.read()


# What to do about a damaged checkpoint, said once for every message below.
EARLIER = ("use an earlier checkpoint of the run (checkpoint-<iteration>.pt, which train.py keeps with "
           "--keep-checkpoints or --save-at) or one written by warpgym train")


def _first_line(e: BaseException) -> str:
    text = str(e).strip()
    return f"{type(e).__name__}: {text.splitlines()[0][:160]}" if text else type(e).__name__


def load_bytes(data: bytes, path: str, device: torch.device) -> dict:
    """A checkpoint from its bytes (``path`` names it in errors). Refuses anything that is not a
    torch file of tensors and plain values with a warpgym checkpoint's keys, and runs no code: every
    failure is a ``ValueError`` that names the file, says what is wrong with it and what to do."""
    if not data:
        raise ValueError(f"{path} is empty (0 bytes): a write that never happened; {EARLIER}")
    if not data.startswith(b"PK\x03\x04"):  # torch.save writes a zip archive
        raise ValueError(f"{path} is not a warpgym checkpoint (not the zip archive torch.save writes: another "
                         f"kind of file); {EARLIER}")
    end = data.rfind(_END)
    declared = struct.unpack_from("<H", data, end + 20)[0] if 0 <= end <= len(data) - 22 else -1
    if end < 0 or declared < 0 or len(data) < end + 22 + declared:  # a zip archive ends with its directory
        raise ValueError(f"{path} is truncated ({len(data)} bytes, its end is missing: a write was cut short or "
                         f"the copy is incomplete); {EARLIER}")
    _check_seal(data, end, path)
    try:
        ckpt = torch.load(io.BytesIO(data), map_location=device, weights_only=True)
    except pickle.UnpicklingError as e:
        raise ValueError(f"{path} was not loaded: it holds pickled objects other than tensors and plain values, "
                         f"which may run code when loaded, or its bytes are damaged ({_first_line(e)}); "
                         f"{EARLIER}, from a source you trust") from e
    except Exception as e:  # noqa: BLE001  (torch reports damage as any of a dozen types)
        raise ValueError(f"{path} is damaged: its bytes do not read back as a torch file ({_first_line(e)}); "
                         f"{EARLIER}") from e
    if not isinstance(ckpt, dict) or any(k not in ckpt for k in REQUIRED):
        have = sorted(ckpt) if isinstance(ckpt, dict) else type(ckpt).__name__
        raise ValueError(f"{path} is a torch file but not a warpgym checkpoint (it has {have}, a checkpoint has "
                         f"{list(REQUIRED)}); {EARLIER}")
    return ckpt


def load(path: str, device: torch.device) -> dict:
    return load_bytes(read_checkpoint_bytes(path), path, device)


def load_for_command(path: str, device: torch.device) -> tuple[str, dict]:
    """For command-line tools: ``path`` is a checkpoint file or a run directory holding checkpoint.pt.
    A missing, damaged or foreign file ends the program with one line that names it (no traceback)."""
    file = os.path.join(path, "checkpoint.pt") if os.path.isdir(path) else path
    try:
        ckpt = load(file, device)
    except (FileNotFoundError, ValueError) as e:
        raise SystemExit(f"error: {e}") from None
    config = ckpt["config"] if isinstance(ckpt["config"], dict) else {}
    if not isinstance(config.get("env_args"), dict) or "task" not in config["env_args"]:
        raise SystemExit(f"error: {file} holds a policy but not the task it was trained on (its config has no "
                         "env_args.task): it was not written by warpgym train; use one that was")
    return file, ckpt


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
    """The trained policy (PPO's actor-critic, or the off-policy learner's policy) and its observation normaliser,
    ready for evaluation: ``policy.act_deterministic(normalize(obs))`` acts, ``policy.actor`` is that action's
    module (agents.export)."""
    from agents.actor_critic import ActorCritic  # noqa: PLC0415
    from agents.normalizer import RunningMeanStd  # noqa: PLC0415

    cfg = ckpt["config"]
    have = (ckpt["spec"]["num_obs"], ckpt["spec"]["num_actions"])
    if have != (num_obs, num_actions):
        raise ValueError(f"checkpoint is for obs/action sizes {have}, the env has {(num_obs, num_actions)}")
    if cfg.get("agent") == "AgentSAC":  # the off-policy learner's: its policy alone (agents.sac)
        from agents.sac.networks import SquashedGaussianPolicy  # noqa: PLC0415

        policy = SquashedGaussianPolicy(num_obs, num_actions, tuple(cfg["actor_dims"]), cfg["layer_norm"],
                                        cfg["log_std_min"], cfg["log_std_max"]).to(device)
    else:
        policy = ActorCritic(num_obs, num_actions, tuple(cfg["net_dims"]), cfg["activation"],
                             num_critic_obs=ckpt["spec"].get("num_critic_obs", 0)).to(device)
    policy.load_state_dict(ckpt["policy"])
    if not cfg["normalize_obs"]:
        return policy, lambda obs: obs
    norm = RunningMeanStd(num_obs, cfg["obs_clip"]).to(device)
    norm.load_state_dict(ckpt["normalizer"])
    return policy, norm


def with_normalizer(ckpt: dict, other: dict, names: tuple[str, str] = ("the checkpoint", "the other")) -> dict:
    """``ckpt`` acting on the inputs that ``other``'s observation statistics give it: its weights, their
    normaliser. A policy whose return decays as training goes on may be following its normaliser: where an
    input's running mean follows the policy's own behaviour (a cart's position), the policy's notion of
    centre moves with it. Played with an earlier normaliser, such a policy recovers; played with a later
    one, an earlier policy decays."""
    for name, c in zip(names, (ckpt, other)):
        if not c["config"].get("normalize_obs", False):
            raise ValueError(f"{name} was trained without an observation normaliser (normalize_obs false): "
                             "it has no statistics to swap; compare two checkpoints that have them")
    tasks = [c["config"]["env_args"].get("task") for c in (ckpt, other)]
    sizes = [c["spec"]["num_obs"] for c in (ckpt, other)]
    if tasks[0] != tasks[1] or sizes[0] != sizes[1]:
        raise ValueError(f"{names[0]} is for {tasks[0]} ({sizes[0]} observations), {names[1]} for {tasks[1]} "
                         f"({sizes[1]}): swap normalisers between checkpoints of one task")
    return {**ckpt, "normalizer": other["normalizer"]}
