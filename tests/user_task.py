"""A task of a user's own, registered under its own name by its module, as ``warpgym train --task
user_task:UserGo1-v0`` imports it: the Go1 on flat ground with tests/user_terms.py's reward, observation and
event."""

from user_terms import EVENTS, OBSERVATIONS, REWARDS

from warpgym.tasks.legged import LEGGED
from warpgym.tasks.registry import register

TASK = register(LEGGED["Go1VelocityFlat-v0"].replace(name="UserGo1-v0", rewards=REWARDS, policy_obs=OBSERVATIONS,
                                                     critic_obs=OBSERVATIONS, events=EVENTS))
