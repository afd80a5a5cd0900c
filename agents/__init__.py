"""agents: PPO for GPU vector environments. Knows torch tensors only (no Warp, Newton or warpgym).

Any env that follows ``agents.protocol`` trains: num_envs, observation/action sizes, reset(),
step(actions) -> obs, reward, terminated, truncated, info, all torch tensors on one device.
"""

from agents.actor_critic import ActorCritic
from agents.config import Config
from agents.normalizer import RunningMeanStd
from agents.ppo import PPO
from agents.runner import OnPolicyRunner
from agents.storage import RolloutStorage

__all__ = ["ActorCritic", "Config", "OnPolicyRunner", "PPO", "RolloutStorage", "RunningMeanStd"]
