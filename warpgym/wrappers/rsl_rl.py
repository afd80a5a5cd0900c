"""warpgym for rsl_rl (``pip install "warpgym[rsl_rl]"``): its ``VecEnv`` with observation groups.

    from rsl_rl.runners import OnPolicyRunner
    env = RslRlVecEnv(LocomotionVecEnv("Ant", num_envs=4096, device="cuda:0"))
    OnPolicyRunner(env, train_cfg, log_dir, device="cuda:0").learn(1000)

Zero copy, except the observations: rsl_rl keeps a reference to the observation it acted on and
stores it only after the next ``step``, which overwrites warpgym's observation buffer in place, so
the adapter hands it a copy (one device-to-device copy per step, into two buffers used by
turns). Rewards, dones and time-outs are warpgym's own buffers (rsl_rl copies them before the
next step).
"""

from __future__ import annotations

import torch

try:
    from rsl_rl.env import VecEnv
    from tensordict import TensorDict
except ImportError as e:  # pragma: no cover - the message is the point
    raise ImportError(f'the rsl_rl adapter needs rsl_rl: pip install "warpgym[rsl_rl]" ({e})') from e

from warpgym.wrappers.common import EpisodeLog, ObsCopies, base_env


class RslRlVecEnv(VecEnv):
    """rsl_rl's ``VecEnv`` over a warpgym vector env. Observation groups: ``policy`` (rsl_rl's
    default for the actor and the critic, as Isaac Lab names it) and, for a task with a critic's
    observation of its own (the legged tasks' ``info["critic_obs"]``), ``critic``: map them with
    ``obs_groups={"actor": ["policy"], "critic": ["critic"]}``, as mjlab's runner maps its own.

    Args:
        env: a warpgym ``LocomotionVecEnv`` (or a Gymnasium wrapper of one).
        log: an ``EpisodeLog`` to feed (optional).
    """

    SHARED = {"obs": False, "reward": True, "done": True, "time_outs": True}
    WHY_COPIED = {"obs": "rsl_rl stores the observation it acted on after the next step, which overwrites it"}

    def __init__(self, env, log: EpisodeLog | None = None):
        self.env = env
        self._base = b = base_env(env)
        self.num_envs, self.num_actions = b.num_envs, b.num_actions
        self.max_episode_length = b.task.episode_length
        self.device = b.device
        self.cfg = {"task": b.task.name}
        self.log = log
        # each group copied by turns (the same reason as the policy's); all toggle together
        self._sources = {"policy": b.obs, **({"critic": b.info["critic_obs"]} if "critic_obs" in b.info else {})}
        self._copies = {name: ObsCopies(src) for name, src in self._sources.items()}
        self._groups = [TensorDict({name: c.buffers[i] for name, c in self._copies.items()},
                                   batch_size=[self.num_envs], device=self.device) for i in (0, 1)]
        self._obs = None
        # a rough task's curriculum state, as rsl_rl logs Isaac Lab's and mjlab's: extras["log"]["Curriculum/..."]
        curriculum = getattr(b, "curriculum", None)
        self._curriculum = curriculum if callable(curriculum) and curriculum() else None

    @property
    def episode_length_buf(self) -> torch.Tensor:
        """Steps into each env's episode: warpgym's own counter, so rsl_rl's random initial episode
        lengths (``init_at_random_ep_len``) do shorten the first episodes."""
        return self._base.episode_steps

    @episode_length_buf.setter
    def episode_length_buf(self, value: torch.Tensor) -> None:
        self._base.episode_steps.copy_(value)

    def _group(self, obs: torch.Tensor) -> TensorDict:
        for name, copies in self._copies.items():
            copies(obs if name == "policy" else self._sources[name])
        return self._groups[self._copies["policy"].index]

    def get_observations(self) -> TensorDict:
        if self._obs is None:
            obs, _ = self.env.reset()
            self._obs = self._group(obs)
        return self._obs

    def step(self, actions: torch.Tensor):
        obs, reward, terminated, truncated, info = self.env.step(actions)
        if self.log is not None:
            self.log.after_step(info)
        self._obs = self._group(obs)
        done = info["_final_obs"]  # terminated | truncated, one buffer
        extras = {"time_outs": info["time_outs"]}
        if self._curriculum is not None:
            extras["log"] = {f"Curriculum/{name}": value for name, value in self._curriculum().items()}
        return self._obs, reward, done, extras

    def close(self):
        self.env.close()
