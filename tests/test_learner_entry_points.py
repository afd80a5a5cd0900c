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
    with pytest.warns(UserWarning):  # skrl copies torch tensors with torch.tensor(): our adapter hands them over
        obs, reward, terminated, truncated, _ = wrapped.step(actions)
    np.testing.assert_array_equal(obs.numpy(), env.obs.numpy())
    np.testing.assert_array_equal(reward.numpy().reshape(-1), env.reward.numpy())
    np.testing.assert_array_equal(truncated.numpy().reshape(-1), env.truncated.numpy())


def test_skrl_trains_on_its_own_wrapper_of_a_suite_env(hopper_vec, tmp_path):
    """skrl's documented loop end to end: wrap_env, its PPO and SequentialTrainer; the episodes it counts are
    the env's (Hopper falls within its first few dozen random steps)."""
    pytest.importorskip("skrl")
    from skrl.agents.torch.ppo import PPO, PPO_CFG
    from skrl.envs.wrappers.torch import wrap_env
    from skrl.memories.torch import RandomMemory
    from skrl.models.torch import DeterministicMixin, GaussianMixin, Model
    from skrl.trainers.torch import SequentialTrainer

    env = wrap_env(hopper_vec, verbose=False)

    class Policy(GaussianMixin, Model):
        def __init__(self, observation_space, action_space, device):
            Model.__init__(self, observation_space=observation_space, action_space=action_space, device=device)
            GaussianMixin.__init__(self, clip_actions=True)
            self.net = torch.nn.Linear(self.num_observations, self.num_actions)
            self.log_std = torch.nn.Parameter(torch.zeros(self.num_actions))

        def compute(self, inputs, role=""):
            return self.net(inputs["observations"]), {"log_std": self.log_std}

    class Value(DeterministicMixin, Model):
        def __init__(self, observation_space, action_space, device):
            Model.__init__(self, observation_space=observation_space, action_space=action_space, device=device)
            DeterministicMixin.__init__(self)
            self.net = torch.nn.Linear(self.num_observations, 1)

        def compute(self, inputs, role=""):
            return self.net(inputs["observations"]), {}

    models = {"policy": Policy(env.observation_space, env.action_space, env.device),
              "value": Value(env.observation_space, env.action_space, env.device)}
    # skrl tracks episodes only while it writes its logs (every 1000 steps: never within these 64)
    cfg = PPO_CFG(rollouts=16, learning_epochs=1, mini_batches=1,
                  experiment={"directory": str(tmp_path), "write_interval": 1000, "checkpoint_interval": 0})
    agent = PPO(models=models, memory=RandomMemory(memory_size=16, num_envs=env.num_envs, device=env.device),
                observation_space=env.observation_space, action_space=env.action_space, device=env.device, cfg=cfg)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        SequentialTrainer(env=env, agents=agent, cfg={"timesteps": 64, "disable_progressbar": True,
                                                      "close_environment_at_exit": False}).train()
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
