"""The learners' own entry points, as their docs tell a user to pass a Gymnasium env: skrl's ``wrap_env(env)``
(its automatic choice) and Stable-Baselines3's env ids. (rsl_rl and rl_games take no Gymnasium env of their own:
warpgym's adapters are their way in, tested in test_wrappers.py.)"""

import warnings

import gymnasium as gym
import numpy as np
import pytest
import torch

import warpgym  # noqa: F401  (registers the envs)


@pytest.fixture(scope="module")
def hopper_vec():
    return gym.make_vec("warpgym/Hopper-v5", num_envs=4, device="cpu")


@pytest.mark.parametrize("which", ["ant_env", "humanoid_env", "hopper_vec"])
def test_skrl_wrap_env_recognises_the_vector_envs_and_passes_their_values(which, request):
    """skrl picks its wrapper from the env class's direct bases: warpgym's envs must show a Gymnasium one.
    The Ant and Humanoid fixtures are of the class gym.make_vec("warpgym/Ant-v0") returns."""
    pytest.importorskip("skrl")
    from skrl.envs.wrappers.torch import wrap_env
    from skrl.envs.wrappers.torch.gymnasium_envs import GymnasiumWrapper

    env = request.getfixturevalue(which)
    assert gym.spec("warpgym/Ant-v0").vector_entry_point.endswith(f":{type(request.getfixturevalue('ant_env')).__name__}")
    wrapped = wrap_env(env, verbose=False)
    assert isinstance(wrapped, GymnasiumWrapper) and wrapped.num_envs == env.num_envs
    assert wrapped.observation_space == env.single_observation_space
    wrapped.reset()
    actions = torch.rand(env.num_envs, env.single_action_space.shape[0]) * 2 - 1
    with warnings.catch_warnings():  # skrl copies the tensors with torch.tensor(), which warns; the values count
        warnings.simplefilter("ignore", UserWarning)
        obs, reward, terminated, truncated, _ = wrapped.step(actions)
    np.testing.assert_array_equal(obs.numpy(), env.obs.numpy())
    np.testing.assert_array_equal(reward.numpy().reshape(-1), env.reward.numpy())
    np.testing.assert_array_equal(truncated.numpy().reshape(-1), env.truncated.numpy())


def test_skrl_trains_on_its_own_wrapper_of_a_suite_env(hopper_vec, tmp_path):
    """skrl's loop end to end on skrl's own wrapper: wrap_env, then the PPO and SequentialTrainer that
    `warpgym train-with skrl` sets up (its models, skrl's published settings); the episodes skrl counts are the
    env's (Hopper falls within its first few dozen random steps)."""
    pytest.importorskip("skrl")
    from argparse import Namespace

    from skrl.envs.wrappers.torch import wrap_env

    from warpgym.cli.train_with import run_skrl

    args = Namespace(task="Hopper-v5", iterations=4)
    with warnings.catch_warnings():  # skrl's wrapper copies the tensors with torch.tensor(), which warns
        warnings.simplefilter("ignore", UserWarning)
        run_skrl(wrap_env(hopper_vec, verbose=False), args, 16, str(tmp_path))
    agent = args.learner_object
    returns = np.asarray(list(agent._track_rewards)).reshape(-1)
    lengths = np.asarray(list(agent._track_timesteps)).reshape(-1)
    assert len(returns) >= 4 and np.isfinite(returns).all() and (lengths < 64).all()


@pytest.mark.parametrize("env_id", ["warpgym/Hopper-v5", "warpgym/Ant-v0"])
def test_stable_baselines3_takes_the_env_id(env_id):
    """SB3's own way in: an env id, made by its make_vec_env (one warpgym world a copy) and trained by its PPO;
    the episodes it counts end as the env ends them."""
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env

    venv = make_vec_env(env_id, n_envs=1, env_kwargs={"max_episode_steps": 16})
    model = PPO("MlpPolicy", venv, n_steps=64, batch_size=32, n_epochs=1, seed=0)
    model.learn(64)
    lengths = [e["l"] for e in model.ep_info_buffer]
    assert lengths and max(lengths) <= 16 and all(np.isfinite(e["r"]) for e in model.ep_info_buffer)
