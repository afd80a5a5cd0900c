"""Deterministic-policy evaluation: each env plays one episode with the action mean."""

from __future__ import annotations

import torch


def reward_terms(info: dict, n: int) -> list[str]:
    """The per-step reward terms an env reports in ``info`` (agents.protocol: Gymnasium's ``reward_*``
    keys, and ``*_penalty``), each a tensor of one value per env."""
    return [k for k, v in info.items() if (k.startswith("reward_") or k.endswith("_penalty"))
            and isinstance(v, torch.Tensor) and v.shape == (n,)]


@torch.no_grad()
def evaluate(env, policy, normalize, max_steps: int, recorder=None) -> dict:
    """Mean return, length and forward speed of the first episode of every env (one host read), and
    the mean episode sum of each reward term the env reports (``eval/reward_forward``, ...).

    Forward speeds are the env's own (``info["episode"]["s"]``, agents.protocol): nothing here computes
    one. An episode still running after ``max_steps`` counts with what it has so far, its speed from
    ``info["episode_so_far"]["s"]`` (0 if the env reports none). A ``recorder`` (agents.protocol) sees
    the env after the reset and after every step."""
    obs, _ = env.reset()
    if recorder is not None:
        recorder.capture(env)
    n = env.num_envs
    dev = obs.device
    finished = torch.zeros(n, dtype=torch.bool, device=dev)
    ret = torch.zeros(n, device=dev)
    length = torch.zeros(n, device=dev)
    out_ret, out_len, out_speed = torch.zeros(n, device=dev), torch.zeros(n, device=dev), torch.zeros(n, device=dev)
    info: dict = {}
    names: list[str] | None = None
    terms = torch.zeros(0, n, device=dev)
    for _ in range(max_steps):
        obs, reward, terminated, truncated, info = env.step(policy.act_deterministic(normalize(obs)))
        if recorder is not None:
            recorder.capture(env)
        if names is None:
            names = reward_terms(info, n)
            terms = torch.zeros(len(names), n, device=dev)
        live = ~finished
        ret += reward * live
        if names:  # an episode's terms stop with it, as its return does
            terms += torch.stack([info[k] for k in names]) * live
        length += live.float()
        ended = (terminated | truncated) & live
        out_ret = torch.where(ended, ret, out_ret)
        out_len = torch.where(ended, length, out_len)
        speed = info.get("episode", {}).get("s")
        if speed is not None:
            out_speed = torch.where(ended, speed, out_speed)
        finished |= ended
    # an episode still running at max_steps counts with what it has so far
    out_ret = torch.where(finished, out_ret, ret)
    out_len = torch.where(finished, out_len, length)
    so_far = info.get("episode_so_far", {}).get("s")
    if so_far is not None:
        out_speed = torch.where(finished, out_speed, so_far)
    means = torch.cat([torch.stack([out_ret.mean(), out_len.mean(), out_speed.mean()]), terms.mean(dim=1)]).tolist()
    r, ln, s = means[:3]
    return {"eval/return": r, "eval/length": ln, "eval/speed": s,
            **{f"eval/{k}": v for k, v in zip(names or [], means[3:])}}
