"""warpgym for RLlib's new API stack (``pip install "warpgym[rllib]"``): one vector env per env runner.

    from ray.rllib.algorithms.ppo import PPOConfig
    config = (PPOConfig().environment(register_rllib_env(), env_config={"task": "Ant", "device": "cuda:0"})
              .env_runners(num_env_runners=0, num_envs_per_env_runner=4096,
                           gym_env_vectorize_mode="vector_entry_point"))

RLlib's ``SingleAgentEnvRunner`` builds its envs with ``gymnasium.make_vec``; with
``gym_env_vectorize_mode="vector_entry_point"`` the creator returns one ``VectorEnv`` and RLlib steps it
as is, so every robot of the runner steps in one warpgym step (one CUDA graph launch).

**Autoreset.** RLlib's runner expects Gymnasium's next-step autoreset: an episode's last step returns
its last observation, and the runner asks for the first observation of the next one with the
following step, whose action is ignored. warpgym resets inside the step that ends an episode
(same-step). The adapter returns ``info["final_obs"]`` for the envs that finished, and in the next step
reports those envs' current observation as the new episode's first, with reward 0 and no done flag.
warpgym steps every world in every step, so that hidden step does move the robot: it runs with zero
actions, and the new episode starts one 1/60 s step after warpgym's reset (its start state spread by one
step of zero torque). warpgym's own episode statistics (``EpisodeLog``) count that step; RLlib's do not.

**Copies.** RLlib keeps episodes as numpy arrays on the host and its connectors take numpy in, so
every step copies the observations, rewards and flags to the host and the actions back (a device sync
per step on a GPU), and RLlib's runner loops over the envs in Python. That is the cost of RLlib's
design, measured in ``benchmarks/learning/learners.py`` (and the runner's own loop, with an env that does
nothing, in ``benchmarks/multi_gpu/rllib_overhead.py``); the torch adapters (rsl_rl, skrl, rl_games) keep
the data on the device.
"""

from __future__ import annotations

import functools

import numpy as np
import torch
from gymnasium.vector import AutoresetMode, VectorEnv

from warpgym.wrappers.common import EpisodeLog, base_env


class RllibVecEnv(VectorEnv):
    """A numpy ``VectorEnv`` with next-step autoreset over a warpgym vector env.

    Args:
        env: a warpgym ``LocomotionVecEnv`` (or a Gymnasium wrapper of one).
        log: an ``EpisodeLog`` to feed with warpgym's episode statistics (optional).
    """

    def __init__(self, env, log: EpisodeLog | None = None):
        self.env = env
        self._base = b = base_env(env)
        self.num_envs = b.num_envs
        self.single_observation_space, self.single_action_space = b.single_observation_space, b.single_action_space
        self.observation_space, self.action_space = b.observation_space, b.action_space
        self.metadata = {**b.metadata, "autoreset_mode": AutoresetMode.NEXT_STEP}
        self.device = b.device
        self.log = log
        # envs whose episode ended in the last step: this step starts their next episode
        self._restarting = torch.zeros(b.num_envs, dtype=torch.bool, device=b.device)
        self._actions = torch.zeros(b.num_envs, b.num_actions, dtype=torch.float32, device=b.device)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        obs, _ = self.env.reset(seed=seed, options=options)
        self._restarting.zero_()
        return obs.cpu().numpy(), {}

    def step(self, actions):
        self._actions.copy_(torch.as_tensor(np.asarray(actions, dtype=np.float32)))
        self._actions.masked_fill_(self._restarting.unsqueeze(1), 0.0)
        obs, reward, terminated, truncated, info = self.env.step(self._actions)
        if self.log is not None:
            self.log.after_step(info)
        restarting = self._restarting
        done = (terminated | truncated) & ~restarting
        # one host copy per step: observation, reward and flags packed side by side, into a new array each
        # time, since RLlib's episodes keep views of the rows it is handed
        packed = torch.cat((torch.where(done.unsqueeze(1), info["final_obs"], obs),
                            torch.stack((reward.masked_fill(restarting, 0.0), (terminated & ~restarting).float(),
                                         (truncated & ~restarting).float()), dim=1)), dim=1).cpu().numpy()
        self._restarting.copy_(done)
        n = self._base.num_obs
        return (packed[:, :n], packed[:, n].astype(np.float64), packed[:, n + 1] > 0.5, packed[:, n + 2] > 0.5, {})

    def close(self, **kwargs):
        self.env.close()


def rllib_env_creator(config: dict) -> RllibVecEnv:
    """RLlib's env creator: ``config`` (RLlib's ``env_config``, plus ``num_envs`` from RLlib) names the task
    (``"Ant"``, ``"Humanoid"`` or one of Gymnasium's suite, ``"Hopper-v5"``...), ``device``, ``seed`` and any
    other argument of its env (``warpgym.envs.make_vec_env``)."""
    from warpgym.envs import make_vec_env

    kwargs = dict(config)
    task = kwargs.pop("task", "Ant")
    return RllibVecEnv(make_vec_env(task, **kwargs))


RLLIB_ENV = "warpgym-rllib"


def register_rllib_env() -> str:
    """Register ``rllib_env_creator`` with Ray under ``RLLIB_ENV`` and return that name, for
    ``PPOConfig().environment(RLLIB_ENV, env_config={"task": ...})``."""
    try:
        from ray.tune.registry import register_env
    except ImportError as e:
        raise ImportError(f'the RLlib adapter needs RLlib: pip install "warpgym[rllib]" ({e})') from e
    register_env(RLLIB_ENV, rllib_env_creator)
    return RLLIB_ENV


_BUILT: dict[str, RllibVecEnv] = {}


def _built(name: str, config: dict) -> RllibVecEnv:
    return _BUILT[name]


def register_built_env(name: str, env: RllibVecEnv) -> str:
    """Register an adapter already built in this process under ``name``, for an env runner in this
    process (``num_env_runners=0``). Ray pickles env creators, and a warpgym env holds device memory:
    the creator Ray keeps names the adapter instead of holding it."""
    from ray.tune.registry import register_env

    _BUILT[name] = env
    register_env(name, functools.partial(_built, name))
    return name
