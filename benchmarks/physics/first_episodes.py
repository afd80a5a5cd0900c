"""Each world's first episode under a policy, counted the same way in any env (plain torch, so that mjlab's
interpreter runs it too: benchmarks/physics/mjlab_side.py and legged_returns.py)."""

from __future__ import annotations


def first_episodes(step, act, obs, num_envs: int, max_steps: int) -> dict:
    """Step until every world's first episode has ended (or ``max_steps``): ``step(actions)`` returns the env's
    (obs, reward, terminated, truncated, ...), ``act(obs)`` the actions. Each world's return (the sum of its
    rewards), length and whether it ended terminated rather than truncated."""
    import torch

    total = torch.zeros(num_envs, dtype=torch.float64)
    length = torch.zeros(num_envs, dtype=torch.long)
    fell = torch.zeros(num_envs, dtype=torch.bool)
    alive = torch.ones(num_envs, dtype=torch.bool)
    with torch.no_grad():
        for _ in range(max_steps):
            obs, reward, terminated, truncated = step(act(obs))[:4]
            terminated, truncated = terminated.cpu(), truncated.cpu()
            total += reward.cpu().double() * alive
            length += alive
            fell |= terminated & alive
            alive &= ~(terminated | truncated)
            if not alive.any():
                break
    return {"returns": total.tolist(), "lengths": length.tolist(), "fell": fell.tolist()}
