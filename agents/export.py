"""A trained policy as a file another program runs without agents or warpgym: the observation normaliser and the
actor's mean in one module, written as ONNX (ONNX Runtime, the robots' own stacks) and as a ``torch.export``
program (``torch.export.load(path).module()``; TorchScript, deprecated in torch 2.13, is not written). Either takes
any batch size. The deterministic action is the actor's mean, as evaluation plays it."""

from __future__ import annotations

import os

import torch
from torch import nn

ONNX_OPSET = 17


class DeployedPolicy(nn.Module):
    """observation (B, num_obs) float32 -> action (B, num_actions): ``actor((obs - mean) / sqrt(var + eps))`` with the
    normalised observation clipped to [-clip, clip], or ``actor(obs)`` for a policy trained without a normaliser."""

    def __init__(self, actor: nn.Sequential, mean: torch.Tensor, var: torch.Tensor, eps: float, clip: float):
        super().__init__()
        self.actor = actor
        self.register_buffer("mean", mean.detach().float().clone())
        self.register_buffer("std", torch.sqrt(var.detach().float() + eps))
        self.clip = float(clip)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.actor(((obs - self.mean) / self.std).clamp(-self.clip, self.clip))


def deployable(ckpt: dict) -> DeployedPolicy:
    """The checkpoint's policy as a DeployedPolicy on the CPU, in evaluation mode."""
    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415

    spec = ckpt["spec"]
    num_obs = spec["num_obs"]
    policy, norm = policy_from_checkpoint(ckpt, num_obs, spec["num_actions"], torch.device("cpu"))
    if isinstance(norm, nn.Module):
        mean, var, eps, clip = norm.mean, norm.var, norm.eps, norm.clip
    else:  # trained without a normaliser: the identity (a clip no input reaches)
        mean, var, eps, clip = torch.zeros(num_obs), torch.ones(num_obs), 0.0, torch.finfo(torch.float32).max
    return DeployedPolicy(policy.actor, mean, var, eps, clip).eval()


def _replace(write, path: str) -> None:
    """``write(tmp)``, then the file at ``path`` whole: a failure leaves the previous file."""
    root, ext = os.path.splitext(path)
    tmp = f"{root}.tmp{ext}"  # the extension kept: torch.export's writer expects .pt2
    try:
        write(tmp)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def write_exported_program(module: DeployedPolicy, num_obs: int, path: str) -> None:
    """``torch.export``'s program of the module (a .pt2 file), the batch dimension free (traced at 2: an example of 1
    would fix it)."""
    batch = torch.export.Dim("batch")
    program = torch.export.export(module, (torch.zeros(2, num_obs),), dynamic_shapes={"obs": {0: batch}})
    _replace(lambda tmp: torch.export.save(program, tmp), path)


def write_onnx(module: DeployedPolicy, num_obs: int, path: str) -> None:
    """ONNX through torch's TorchScript-based exporter (it needs the ``onnx`` package: ``pip install onnx``), the
    batch size left free: input ``obs``, output ``actions``."""
    import warnings  # noqa: PLC0415

    def write(tmp):
        with warnings.catch_warnings():  # the exporter's notice that a newer one exists
            warnings.simplefilter("ignore", DeprecationWarning)
            torch.onnx.export(module, (torch.zeros(1, num_obs),), tmp, dynamo=False, opset_version=ONNX_OPSET,
                              input_names=["obs"], output_names=["actions"],
                              dynamic_axes={"obs": {0: "batch"}, "actions": {0: "batch"}})

    _replace(write, path)
