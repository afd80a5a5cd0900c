"""The learners a run can pick, by name: each its config class and its runner. A checkpoint's config names its
learner by ``agent`` (ElegantRL's field), which ``by_agent`` reads back."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class Algo:
    name: str  # as `warpgym train --algo` writes it
    agent: str  # the config's ``agent`` field
    config: Callable  # the config class
    runner: Callable  # (env, cfg, run_dir=..., eval_env=..., ...) -> a TrainingLoop


def _ppo() -> Algo:
    from agents.config import Config  # noqa: PLC0415
    from agents.runner import OnPolicyRunner  # noqa: PLC0415

    return Algo("ppo", "AgentPPO", Config, OnPolicyRunner)


def _sac() -> Algo:
    from agents.sac import OffPolicyRunner, SACConfig  # noqa: PLC0415

    return Algo("sac", "AgentSAC", SACConfig, OffPolicyRunner)


ALGOS: dict[str, Callable[[], Algo]] = {"ppo": _ppo, "sac": _sac}


def algo(name: str) -> Algo:
    if name not in ALGOS:
        raise ValueError(f"algo={name!r}: choose one of {sorted(ALGOS)}")
    return ALGOS[name]()


def by_agent(agent: str | None) -> Algo:
    """The learner of a config's ``agent`` field (a config without one is PPO's, as every run before SAC)."""
    for make in ALGOS.values():
        a = make()
        if a.agent == (agent or "AgentPPO"):
            return a
    raise ValueError(f"agent={agent!r}: this package has {sorted(m().agent for m in ALGOS.values())}")
