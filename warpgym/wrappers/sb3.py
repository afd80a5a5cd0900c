"""warpgym for Stable-Baselines3 (``pip install "warpgym[sb3]"``): its numpy ``VecEnv``.

The slow path, for CPU users and for comparison: SB3 works in numpy, so every step copies the
observations, rewards and flags to the host and the actions back, and builds SB3's list of one
info dict per env. On a GPU most of the time goes there, not into the physics.
"""

from __future__ import annotations

import numpy as np

try:
    from stable_baselines3.common.vec_env import VecEnv
except ImportError as e:  # pragma: no cover
    raise ImportError(f'the SB3 adapter needs stable-baselines3: pip install "warpgym[sb3]" ({e})') from e

from warpgym.wrappers.common import EpisodeLog, base_env


class Sb3VecEnv(VecEnv):
    """SB3's ``VecEnv`` over a warpgym vector env. Finished envs report
    ``terminal_observation``, ``TimeLimit.truncated`` and ``episode`` (``r``, ``l``) as SB3's own
    ``VecMonitor`` and ``TimeLimit`` would.

    Args:
        env: a warpgym ``LocomotionVecEnv`` (or a Gymnasium wrapper of one).
        log: an ``EpisodeLog`` to feed (optional).
    """

    SHARED = {"obs": False, "reward": False, "done": False}
    WHY_COPIED = {k: "SB3 takes numpy arrays on the host" for k in SHARED}

    def __init__(self, env, log: EpisodeLog | None = None):
        self.env = env
        self._base = b = base_env(env)
        super().__init__(b.num_envs, b.single_observation_space, b.single_action_space)
        self.log = log
        self._actions = None

    def reset(self):
        obs, _ = self.env.reset(seed=self._seeds[0] if self._seeds and self._seeds[0] is not None else None)
        self._reset_seeds()
        return obs.cpu().numpy().copy()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        obs, reward, terminated, truncated, info = self.env.step(np.asarray(self._actions, dtype=np.float32))
        if self.log is not None:
            self.log.after_step(info)
        done = info["_final_obs"]
        obs_np, reward_np, done_np = obs.cpu().numpy().copy(), reward.cpu().numpy().copy(), done.cpu().numpy().copy()
        infos: list[dict] = [{} for _ in range(self.num_envs)]
        ended = np.flatnonzero(done_np)
        if ended.size:
            final = info["final_obs"][done].cpu().numpy()
            term, trunc = terminated[done].cpu().numpy(), truncated[done].cpu().numpy()
            ep = info["episode"]
            ret, length = ep["r"][done].cpu().numpy(), ep["l"][done].cpu().numpy()
            for j, i in enumerate(ended):
                infos[i] = {"terminal_observation": final[j], "TimeLimit.truncated": bool(trunc[j] and not term[j]),
                            "episode": {"r": float(ret[j]), "l": int(length[j])}}
        return obs_np, reward_np, done_np, infos

    def close(self) -> None:
        self.env.close()

    def get_attr(self, attr_name, indices=None):
        return [getattr(self._base, attr_name)] * len(self._get_indices(indices))

    def set_attr(self, attr_name, value, indices=None) -> None:
        raise AttributeError(f"set_attr({attr_name!r}): warpgym's envs share one simulation and set no per-env "
                             "attributes")

    def env_method(self, method_name, *method_args, indices=None, **method_kwargs):
        raise AttributeError(f"env_method({method_name!r}): warpgym's envs are one batched simulation, not "
                             "separate env objects")

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False] * len(self._get_indices(indices))
