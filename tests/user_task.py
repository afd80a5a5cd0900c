"""Tasks of a user's own, registered under their own names by their module, as ``warpgym train --task
user_task:UserGo1-v0`` imports it: the Go1 on flat ground with tests/user_terms.py's reward, observation and
event, Gymnasium's Hopper and warpgym's Ant each with its reward and termination."""

from user_terms import (EVENTS, OBSERVATIONS, REWARDS, ROBOT_REWARDS, ROBOT_TERMINATIONS, SUITE_REWARDS,
                        SUITE_TERMINATIONS)

from warpgym.tasks.legged import LEGGED
from warpgym.tasks.registry import register
from warpgym.tasks.robots import ANT
from warpgym.tasks.suite import SUITE

TASK = register(LEGGED["Go1VelocityFlat-v0"].replace(name="UserGo1-v0", rewards=REWARDS, policy_obs=OBSERVATIONS,
                                                     critic_obs=OBSERVATIONS, events=EVENTS))
HOPPER = register(SUITE["Hopper-v5"].replace(name="UserHopper-v5", rewards=SUITE_REWARDS,
                                              terminations=SUITE_TERMINATIONS))
ANT_TASK = register(ANT.replace(name="UserAnt", rewards=ROBOT_REWARDS, terminations=ROBOT_TERMINATIONS))
