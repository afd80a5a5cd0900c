"""The ElegantRL tutorial's pair, ``IsaacVecEnv`` / ``IsaacOneEnv``, as thin adapters.

    env_args = {"env_num": 4096, "env_name": "Ant", "max_step": 1000, "state_dim": 60,
                "action_dim": 8, "if_discrete": False, "target_return": 14000.0, "device_id": 0}
    env = build_env(IsaacVecEnv, env_args)
    state = env.reset()                                   # (env_num, state_dim) on the GPU
    state, reward, done, info = env.step(action)          # done = terminated | truncated
"""

from __future__ import annotations

import numpy as np
import torch

from warpgym.sim.device import default_device
from warpgym.envs import make_vec_env


def _device(device_id) -> str:
    if device_id is None:
        return default_device()
    return "cpu" if int(device_id) < 0 else f"cuda:{int(device_id)}"


class IsaacVecEnv:
    def __init__(self, env_name: str = "Ant", env_num: int = 4096, device_id: int | None = None,
                 max_step: int | None = None, state_dim: int | None = None, action_dim: int | None = None,
                 if_discrete: bool = False, target_return: float | None = None, if_print: bool = False,
                 seed: int = 0):
        if if_discrete:
            raise ValueError(f"if_discrete=True: {env_name} has continuous actions; pass if_discrete=False")
        self.env = make_vec_env(env_name, num_envs=env_num, device=_device(device_id), seed=seed,
                                    max_episode_steps=max_step)
        for name, given, actual in (("state_dim", state_dim, self.env.num_obs),
                                    ("action_dim", action_dim, self.env.num_actions)):
            if given is not None and given != actual:
                raise ValueError(f"{name}={given} but {env_name} has {actual}: pass {name}={actual}")
        self.env_name, self.env_num, self.max_step = env_name, env_num, self.env.task.episode_length
        self.state_dim, self.action_dim = self.env.num_obs, self.env.num_actions
        self.if_discrete = False
        self.target_return = target_return
        self.device = self.env.device
        if if_print:
            print(f"{type(self).__name__}: {self.env}")

    def reset(self) -> torch.Tensor:
        return self.env.reset()[0]

    def step(self, action: torch.Tensor):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated | truncated, info


class IsaacOneEnv(IsaacVecEnv):
    """One env, numpy in and out: the ElegantRL tutorial's evaluation env (``env_num`` is 1)."""

    def __init__(self, env_name: str = "Ant", device_id: int | None = None, env_num: int = 1, **kwargs):
        if env_num != 1:
            raise ValueError(f"env_num={env_num}: IsaacOneEnv is a single env; use IsaacVecEnv for more")
        super().__init__(env_name, env_num=1, device_id=device_id, **kwargs)

    def reset(self) -> np.ndarray:
        return super().reset()[0].cpu().numpy().copy()

    def step(self, action):
        a = torch.as_tensor(np.asarray(action, np.float32).reshape(1, -1), device=self.device)
        obs, reward, done, info = super().step(a)
        d = bool(done[0])
        state = info["final_obs"][0] if d else obs[0]
        return state.cpu().numpy().copy(), float(reward[0]), d, {}


def build_env(env_class, env_args: dict):
    """Call ``env_class`` with the ``env_args`` it accepts (the ElegantRL tutorial's ``build_env``)."""
    import inspect  # noqa: PLC0415

    params = inspect.signature(env_class).parameters
    kwargs = {k: v for k, v in env_args.items() if k in params}
    return env_class(**kwargs)
