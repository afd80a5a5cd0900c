"""The small vector-env protocol the learner consumes.

An env needs ``num_envs``; observation and action sizes, as ``num_obs``/``num_actions`` or as
``single_observation_space.shape``/``single_action_space.shape``; ``reset() -> (obs, info)``; and
``step(actions) -> (obs, reward, terminated, truncated, info)``, everything a torch tensor on one
device. Finished envs reset inside the step (Gymnasium's same-step autoreset): ``info["final_obs"]``
holds their last observation, masked by ``info["_final_obs"]``. Optional:
``info["episode"] = {"r": return, "l": length, "s": forward speed, "_r": mask}`` for logging;
``info["episode_so_far"]`` with the same keys for the episode in progress after the step (what an
evaluation cut short reports); ``max_episode_steps`` for evaluation; and reward terms, each step's
parts of the reward as tensors of one value per env under Gymnasium's ``reward_*`` (or ``*_penalty``)
keys of ``info``, whose episode sums the evaluation logs beside the return. The learner computes no
speed of its own: it averages the env's.

Optional, for an asymmetric actor-critic: ``num_critic_obs``, the width of a second observation that the critic
sees instead of the policy's (privileged state, no noise). ``reset()``'s info then holds ``info["critic_obs"]``,
every step's info ``info["critic_obs"]`` and ``info["final_critic_obs"]`` (masked like ``final_obs``).
``info["episode"]`` may carry further per-episode statistics beside ``r``, ``l`` and ``s`` (a tracking error,
say), each a tensor of one value per env read where ``_r`` is set: training logs their means as
``episode/<key>`` and evaluation as ``eval/<key>``. ``stagger_episodes() -> (obs, info)``, when the env has it,
resets every env as ``reset()`` does, with its elapsed steps drawn uniformly over the time limit
(``Config.stagger_episodes``).

Optional: ``fault_counters() -> {name: device tensor}``, running totals of things that should
never happen (NaN actions, physics blow-ups, dropped constraints), with ``FAULT_HELP = {name: text}``.
The runner logs them in every row (``faults/<name>``, summed over processes) and warns once per
counter when it first rises above zero.

Optional: ``curriculum() -> {name: device scalar}``, the env's curriculum state as means over its envs (the mean
terrain level, say), read when a row is logged. The runner logs each as ``curriculum/<name>``, the mean over every
env of every process.

Optional too: ``graph_capturable = True`` declares that ``step`` can be recorded into a torch CUDA
graph and replayed: it never waits on the host, and its outputs are persistent tensors that each
step overwrites. The runner then captures whole rollouts.

An evaluation recorder (``OnPolicyRunner(eval_recorder=...)``, e.g. a video clip) has
``capture(env)``, called after the evaluation's reset and after each of its steps, ``finish(iteration,
samples)`` after the episode, and ``close()`` at the end of training. The runner waits for none of
them: anything slow (drawing, encoding) belongs elsewhere.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch


@dataclass(frozen=True)
class EnvSpec:
    num_envs: int
    num_obs: int
    num_actions: int
    device: torch.device
    max_episode_steps: int
    graph_capturable: bool = False
    num_critic_obs: int = 0  # 0: the critic sees the policy's observation


def _size(env, attr: str, space: str) -> int:
    if hasattr(env, attr):
        return int(getattr(env, attr))
    if hasattr(env, space):
        shape = getattr(env, space).shape
        if len(shape) != 1:
            raise ValueError(f"{space} has shape {shape}; the learner takes flat (1-D) observations and actions")
        return int(shape[0])
    raise TypeError(f"{type(env).__name__} has neither {attr} nor {space}: it does not follow agents.protocol")


def env_spec(env) -> EnvSpec:
    if not hasattr(env, "num_envs"):
        raise TypeError(f"{type(env).__name__} has no num_envs: it does not follow agents.protocol")
    device = getattr(env, "device", None)
    if device is None:
        raise TypeError(f"{type(env).__name__} has no device attribute: set env.device to its torch device")
    steps = getattr(env, "max_episode_steps", None)
    if steps is None:
        steps = getattr(getattr(env, "task", None), "episode_length", 1000)
    critic = getattr(env, "num_critic_obs", 0) or 0
    if isinstance(critic, bool) or not isinstance(critic, int) or critic < 0:
        raise TypeError(f"{type(env).__name__}.num_critic_obs={critic!r}: give the critic observation's width, or 0")
    return EnvSpec(int(env.num_envs), _size(env, "num_obs", "single_observation_space"),
                   _size(env, "num_actions", "single_action_space"), torch.device(device), int(steps),
                   bool(getattr(env, "graph_capturable", False)), int(critic))


def critic_obs_of(info: dict, env) -> torch.Tensor:
    """The critic's observation in a reset's or step's info (agents.protocol), or a clear error."""
    critic = info.get("critic_obs") if isinstance(info, dict) else None
    if critic is None:
        raise TypeError(f"{type(env).__name__} declares num_critic_obs but its reset() info has no 'critic_obs': "
                        "return the critic's observation there (agents.protocol)")
    return critic
