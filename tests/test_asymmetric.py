"""agents' asymmetric actor-critic: a critic that sees an observation of its own (agents.protocol's
``num_critic_obs``), its own normaliser, and what the runner keeps and checks of it; staggered starts and the
env's own episode statistics."""

import pytest
import torch
from gymnasium import spaces
from point_mass import PointMassVecEnv

from agents import Config, OnPolicyRunner


class HiddenPositionMass(PointMassVecEnv):
    """The point mass whose policy sees only its velocity, while the critic sees position and velocity: the
    return depends on the position, so only the critic that sees it can predict it. Each episode also reports the
    distance it ended at (an extra statistic) and the env can stagger its episodes."""

    def __init__(self, num_envs=64, seed=0, privileged=True):
        super().__init__(num_envs, seed=seed)
        self.single_observation_space = spaces.Box(-float("inf"), float("inf"), (2,))
        self.num_critic_obs = 4 if privileged else 0
        self.staggered = 0

    def reset(self, seed=None):
        full, _ = super().reset(seed)
        return full[:, 2:].clone(), {"critic_obs": full.clone()}

    def stagger_episodes(self):
        obs, info = self.reset()
        self.staggered += 1
        self.t = torch.randint(0, self.max_episode_steps, (self.num_envs,), dtype=torch.int32, generator=self.gen)
        return obs, info

    def step(self, actions):
        full, reward, terminated, truncated, info = super().step(actions)
        final = info["final_obs"]
        info = {"final_obs": final[:, 2:], "_final_obs": truncated, "critic_obs": full.clone(),
                "final_critic_obs": final,
                "episode": {"r": torch.zeros(self.num_envs), "l": torch.zeros(self.num_envs),
                            "distance": final[:, :2].norm(dim=1), "_r": truncated}}
        return full[:, 2:].clone(), reward, terminated, truncated, info


def config(**more):
    return Config(**{**dict(net_dims=(32, 32), horizon_len=25, minibatch_size=400, repeat_times=4, learning_rate=3e-3,
                            eval_gap=1e9, save_gap=10**6, seed=0), **more})


def test_the_critic_that_sees_the_position_values_it():
    """The critic sees the position the policy does not: after training, a mass at rest at the origin is worth
    more to it than one at rest 2.8 m out (whose steps each cost about 2.8), by most of the difference in what the
    two can still collect; through the policy's velocity alone the two look the same."""
    runner = OnPolicyRunner(HiddenPositionMass(64), config(reward_scale=0.01), print_fn=lambda s: None)
    runner.learn(max_iterations=20)
    states = torch.tensor([[0.0, 0.0, 0.0, 0.0], [2.0, 2.0, 0.0, 0.0]])
    home, far = runner.policy.value(runner.normalize_critic(states)).tolist()
    assert home - far > 0.3, (home, far)


def test_the_critic_reads_its_own_observation_and_normaliser(tmp_path):
    env = HiddenPositionMass(16)
    runner = OnPolicyRunner(env, config(minibatch_size=200), run_dir=str(tmp_path), print_fn=lambda s: None)
    assert runner.policy.critic[0].in_features == 4 and runner.policy.actor[0].in_features == 2
    runner.learn(max_iterations=2)
    s = runner.storage
    assert s.critic_obs.shape == (25, 16, 4) and s.obs.shape == (25, 16, 2)
    # the critic's normaliser learnt the positions' spread (at least that of the starts, uniform in [-2, 2]: 4/3),
    # the policy's only the velocities'
    assert float(runner.critic_normalizer.var[:2].mean()) > 1.0
    assert runner.normalizer.mean.shape == (2,) and runner.critic_normalizer.mean.shape == (4,)
    saved = torch.load(runner.save(), weights_only=True)
    assert saved["spec"]["num_critic_obs"] == 4 and "critic_normalizer" in saved
    # a checkpoint of the symmetric critic does not load into the asymmetric one: one line naming the sizes
    other = OnPolicyRunner(HiddenPositionMass(16, privileged=False), config(minibatch_size=200),
                           run_dir=str(tmp_path / "sym"), print_fn=lambda s: None)
    with pytest.raises(ValueError, match="critic-obs sizes"):
        other.load(runner.save(str(tmp_path / "asym.pt")))


def test_episodes_start_staggered_and_the_envs_statistics_are_logged():
    env = HiddenPositionMass(32)
    runner = OnPolicyRunner(env, config(minibatch_size=400, stagger_episodes=True), print_fn=lambda s: None)
    history = runner.learn(max_iterations=3)
    assert env.staggered == 1
    # staggered, episodes end within the first iteration (25 of the 50 steps); unstaggered, none would
    assert history[0]["episodes"] > 0
    assert all(r["episode/distance"] is None or r["episode/distance"] >= 0 for r in history)
    assert any(r["episode/distance"] for r in history)
    with pytest.raises(ValueError, match="stagger_episodes"):
        OnPolicyRunner(PointMassVecEnv(8), Config(stagger_episodes=True, horizon_len=4, minibatch_size=32),
                       print_fn=lambda s: None)
