"""warpgym for rl_games (``pip install "warpgym[rl_games]"``), the learner Isaac Gym shipped with.

    register_rl_games()                      # the "warpgym" vecenv and env configuration
    Runner().load(config(task="Ant", num_envs=4096, device="cuda:0")); runner.run({"train": True})

rl_games takes tensors as they come (its ``is_tensor_obses`` path) and copies the observation into
its rollout buffer before the next step, so everything here is warpgym's own buffer: zero copies.
Time-outs (truncated and not terminated) go in ``infos["time_outs"]``, which rl_games bootstraps with
``value_bootstrap``.
"""

from __future__ import annotations

try:
    from rl_games.common import env_configurations, vecenv
    from rl_games.common.ivecenv import IVecEnv
except ImportError as e:  # pragma: no cover
    raise ImportError(f'the rl_games adapter needs rl_games: pip install "warpgym[rl_games]" ({e})') from e

from warpgym.wrappers.common import EpisodeLog, base_env

NAME = "warpgym"


class RlGamesVecEnv(IVecEnv):
    """rl_games' ``IVecEnv`` over a warpgym vector env.

    Args:
        env: a warpgym ``LocomotionVecEnv`` (or a Gymnasium wrapper of one).
        log: an ``EpisodeLog`` to feed (optional).
    """

    SHARED = {"obs": True, "reward": True, "done": True, "time_outs": True}
    WHY_COPIED: dict = {}

    def __init__(self, env, log: EpisodeLog | None = None):
        self.env = env
        self._base = base_env(env)
        self.log = log

    def step(self, actions):
        obs, reward, terminated, truncated, info = self.env.step(actions)
        if self.log is not None:
            self.log.after_step(info)
        return obs, reward, info["_final_obs"], {"time_outs": info["time_outs"]}

    def reset(self):
        obs, _ = self.env.reset()
        return obs

    def get_number_of_agents(self):
        return 1

    def get_env_info(self):
        b = self._base
        return {"action_space": b.single_action_space, "observation_space": b.single_observation_space}

    def close(self):
        self.env.close()


def register_rl_games(make_env) -> None:
    """Register ``make_env()`` (returning an ``RlGamesVecEnv``) under the name "warpgym", both as
    rl_games' vecenv type and as its env configuration: a config then says ``env_name: warpgym``."""
    vecenv.register(NAME, lambda config_name, num_actors, **kwargs: make_env())
    env_configurations.register(NAME, {"vecenv_type": NAME, "env_creator": lambda **kwargs: None})
