"""The Ant and Humanoid vector envs: spaces, every observation term and the reward against an
independent torch implementation, dones, resets, seeding, Gymnasium's contract and bad input."""

import gymnasium as gym
import numpy as np
import pytest
import torch
from gymnasium.vector import AutoresetMode

import reference
import warpgym  # noqa: F401  (registers the ids)
from warpgym.envs import LocomotionVecEnv
from warpgym.envs.elegantrl import IsaacOneEnv, IsaacVecEnv, build_env


@pytest.fixture(params=["ant", "humanoid"])
def env(request, ant_env, humanoid_env):
    return {"ant": ant_env, "humanoid": humanoid_env}[request.param]


def test_spaces_shapes_and_dtypes(env):
    expected = {"Ant": (60, 8), "Humanoid": (108, 21)}[env.task.name]
    assert (env.num_obs, env.num_actions) == expected
    assert env.single_observation_space.shape == (expected[0],)
    assert env.single_action_space.shape == (expected[1],)
    assert np.all(env.single_action_space.low == -1) and np.all(env.single_action_space.high == 1)
    assert env.observation_space.shape == (env.num_envs, expected[0])
    assert env.metadata["autoreset_mode"] == AutoresetMode.SAME_STEP
    obs, info = env.reset(seed=1)
    assert obs.shape == (env.num_envs, expected[0]) and obs.dtype == torch.float32
    obs, rew, term, trunc, info = env.step(torch.zeros(env.num_envs, env.num_actions))
    assert rew.shape == (env.num_envs,) and rew.dtype == torch.float32
    assert term.dtype == torch.bool and trunc.dtype == torch.bool
    assert env.observation_space.contains(obs.numpy())
    assert {"final_obs", "_final_obs", "episode", "_episode", "nan_actions", "diverged"} <= set(info)


def test_observation_and_reward_match_an_independent_torch_implementation(env):
    env.reset(seed=2)
    sim, task = env.sim, env.task
    gen = torch.Generator().manual_seed(0)
    checked = 0
    for _ in range(12):
        before = reference.potentials(sim.acquire_actor_root_state_tensor(), task)
        actions = torch.rand(env.num_envs, env.num_actions, generator=gen) * 2.4 - 1.2  # some beyond the clip
        obs, rew, term, trunc, _ = env.step(actions)
        ref_obs = reference.observation(sim, task, actions)
        progress = reference.potentials(sim.acquire_actor_root_state_tensor(), task) - before
        ref_rew = reference.reward(ref_obs, actions, progress, task, sim.motor_gear_np)
        live = ~(term | trunc)  # finished envs were reset after their observation was taken
        torch.testing.assert_close(obs[live], ref_obs[live], atol=2e-4, rtol=1e-4)
        torch.testing.assert_close(rew[live], ref_rew[live], atol=2e-3, rtol=1e-4)
        checked += int(live.sum())
    assert checked >= 6 * env.num_envs


def test_contact_terms_are_live(ant_env):
    """The foot force/torque block is not stuck at zero once the ant stands on the ground (1 s after
    the reset: with the Ant's 0.1 kg m^2 armature a robot may still rock on three feet at 0.5 s)."""
    ant_env.reset(seed=3)
    for _ in range(60):
        obs, *_ = ant_env.step(torch.zeros(ant_env.num_envs, ant_env.num_actions))
    feet = obs[:, 28:52].view(ant_env.num_envs, 4, 6)
    assert torch.all(feet[:, :, 2] > 0)  # upward force on each foot, scaled by 0.1


def test_low_torso_terminates_with_death_cost_and_only_that_env_resets(ant_env):
    env = ant_env
    env.reset(seed=4)
    sim = env.sim
    for _ in range(3):
        env.step(torch.zeros(env.num_envs, env.num_actions))
    root = sim.acquire_actor_root_state_tensor().clone()
    dof_before = sim.dof_pos.clone()
    root[1, 2] = 0.15  # below the 0.31 m termination height
    sim.set_actor_root_state_tensor_indexed(root, torch.tensor([1]))
    obs, rew, term, trunc, info = env.step(torch.zeros(env.num_envs, env.num_actions))
    assert term.tolist() == [False, True, False, False] and not trunc.any()
    assert rew[1].item() == pytest.approx(env.task.death_cost)
    assert info["_final_obs"].tolist() == [False, True, False, False]
    assert info["final_obs"][1, 0] < env.task.termination_height
    assert obs[1, 0].item() == pytest.approx(sim.spec.start_height)  # the new episode's first observation
    assert info["episode"]["l"][1].item() == 4 and info["_episode"][1]
    # the others carried on: their joints moved by one step only
    others = [0, 2, 3]
    assert (sim.dof_pos[others] - dof_before[others]).abs().max() < 0.2
    assert sim.acquire_actor_root_state_tensor()[others, 2].min() > 0.3


def test_truncation_at_episode_length_sets_final_obs_and_a_fall_then_is_both():
    env = LocomotionVecEnv("Ant", num_envs=2, device="cpu", max_episode_steps=5)
    env.reset(seed=0)
    for t in range(5):
        if t == 4:  # robot 1 falls on the last step: terminated and, as Gymnasium's TimeLimit says, truncated
            root = env.sim.acquire_actor_root_state_tensor().clone()
            root[1, 2] = 0.15
            env.sim.set_actor_root_state_tensor_indexed(root, torch.tensor([1]))
        obs, rew, term, trunc, info = env.step(torch.zeros(2, env.num_actions))
        if t < 4:
            assert not trunc.any()
    assert trunc.tolist() == [True, True] and term.tolist() == [False, True]
    assert info["time_outs"].tolist() == [True, False]  # only robot 0's episode is bootstrapped
    assert info["_final_obs"].all()
    assert not torch.allclose(info["final_obs"], obs)  # the final observation is not the reset one
    assert info["episode"]["l"].tolist() == [5, 5]
    torch.testing.assert_close(obs[:, 0], torch.full((2,), env.sim.spec.start_height))
    # an explicit reset ends no episode: the flags clear and the ended episodes' statistics stay
    env.reset()
    assert not (env.terminated.any() or env.truncated.any() or env.info["time_outs"].any())
    assert env.info["episode"]["l"].tolist() == [5, 5]


def test_same_seed_same_trajectory(ant_env):
    def rollout(seed):
        obs, _ = ant_env.reset(seed=seed)
        out = [obs.flatten().clone()]
        gen = torch.Generator().manual_seed(7)
        for _ in range(15):
            obs, rew, *_ = ant_env.step(torch.rand(4, 8, generator=gen) * 2 - 1)
            out.append(torch.cat([obs.flatten(), rew]))
        return torch.cat(out)

    a, b, c = rollout(11), rollout(11), rollout(12)
    torch.testing.assert_close(a, b, atol=1e-6, rtol=0)
    assert (a - c).abs().max() > 1e-3  # another seed draws other reset noise


def test_nan_actions_are_zeroed_and_counted(ant_env):
    ant_env.reset(seed=5)
    before = int(ant_env.fault_counters()["nan_actions"])
    actions = torch.zeros(4, 8)
    actions[2, 3] = float("nan")
    actions[2, 5] = float("inf")
    obs, rew, term, trunc, info = ant_env.step(actions)
    assert info["nan_actions"].tolist() == [0, 0, 2, 0]
    assert int(ant_env.fault_counters()["nan_actions"]) == before + 2  # the running total the runner logs
    assert torch.isfinite(obs).all() and torch.isfinite(rew).all()
    assert ant_env.actions[2].abs().max() == 0  # what reached the physics


def test_diverged_state_is_reset_and_flagged(ant_env):
    ant_env.reset(seed=6)
    ant_env.sim.dof_vel[0, 2] = float("nan")
    ant_env.sim.root_vel[3, 0] = 1e6  # a blow-up that stays finite
    before = int(ant_env.fault_counters()["diverged_resets"])
    obs, rew, term, trunc, info = ant_env.step(torch.zeros(4, 8))
    assert info["diverged"].tolist() == [True, False, False, True]
    assert int(ant_env.fault_counters()["diverged_resets"]) == before + 2
    assert term[0] and term[3] and rew[0] == 0 and rew[3] == 0
    assert torch.isfinite(obs).all() and torch.isfinite(info["final_obs"]).all()
    assert torch.isfinite(ant_env.sim.dof_vel).all()
    obs, rew, term, trunc, info = ant_env.step(torch.zeros(4, 8))  # and it runs on normally
    assert not info["diverged"].any() and torch.isfinite(obs).all()


@pytest.mark.parametrize(
    "actions, error, text",
    [
        (torch.zeros(4, 7), ValueError, r"shape \(4, 7\); expected \(4, 8\)"),
        (torch.zeros(8), ValueError, r"shape \(8,\)"),
        (torch.zeros(4, 8, dtype=torch.float64), TypeError, "float64"),
        (torch.zeros(4, 8, device="meta"), ValueError, "meta"),
        ([[0.0] * 8] * 4, TypeError, "torch.Tensor"),  # numpy arrays are taken (test_wrappers.py); lists are not
    ],
)
def test_bad_actions_are_refused(ant_env, actions, error, text):
    with pytest.raises(error, match=text):
        ant_env.step(actions)


def test_task_settings_reach_the_sim():
    env = LocomotionVecEnv("Ant", num_envs=1, device="cpu", substeps=4, max_episode_steps=7,
                           physics={"solver_iterations": 3})
    assert env.sim.substeps == 4 and env.sim.sub_dt == pytest.approx(1 / 240)
    assert env.task.episode_length == 7 and env.sim.solver.mjw_model.opt.iterations == 3


def test_bad_task_settings_are_refused():
    with pytest.raises(ValueError, match="'Spider'"):
        LocomotionVecEnv("Spider", num_envs=1, device="cpu")
    with pytest.raises(ValueError, match="episode_length=0"):
        LocomotionVecEnv("Ant", num_envs=1, device="cpu", max_episode_steps=0)
    with pytest.raises(ValueError, match="unknown task setting"):
        LocomotionVecEnv("Ant", num_envs=1, device="cpu", gravity=3.0)


def test_gymnasium_registration_and_checker():
    envs = gym.make_vec("warpgym/Ant-v0", num_envs=2, device="cpu")
    assert isinstance(envs, LocomotionVecEnv) and envs.num_envs == 2
    assert envs.task.episode_length == 1000
    one = gym.make("warpgym/Humanoid-v0")
    from gymnasium.utils.env_checker import check_env

    check_env(one.unwrapped, skip_render_check=True)
    obs, _ = one.reset(seed=0)
    assert obs.shape == (108,) and obs.dtype == np.float32
    obs, rew, term, trunc, info = one.step(one.action_space.sample())
    assert isinstance(rew, float) and one.observation_space.contains(obs)


def test_elegantrl_pair_from_the_seeds_env_args():
    env_args = {"env_num": 3, "env_name": "Ant", "max_step": 1000, "state_dim": 60, "action_dim": 8,
                "if_discrete": False, "target_return": 14000.0, "device_id": -1, "if_print": False}
    env = build_env(IsaacVecEnv, env_args)
    assert (env.env_num, env.state_dim, env.action_dim, env.max_step) == (3, 60, 8, 1000)
    state = env.reset()
    assert state.shape == (3, 60)
    state, reward, done, info = env.step(torch.zeros(3, 8))
    assert state.shape == (3, 60) and reward.shape == (3,) and done.dtype == torch.bool
    one = build_env(IsaacOneEnv, env_args | {"env_num": 1})
    s = one.reset()
    assert isinstance(s, np.ndarray) and s.shape == (60,)
    s, r, d, _ = one.step(np.zeros(8))
    assert isinstance(r, float) and isinstance(d, bool)
    with pytest.raises(ValueError, match="state_dim=61 but Ant has 60"):
        IsaacVecEnv("Ant", env_num=1, device_id=-1, state_dim=61)


def test_replayed_cpu_graph_steps_exactly_like_launches_from_python():
    # Warp records a CPU step's launches once and replays them in C++; nothing may be left out
    # (a launch that ran only while recording would leave its buffer stale on every replay)
    runs = []
    for replay in (True, False):
        env = LocomotionVecEnv("Ant", num_envs=4, device="cpu", seed=2, max_episode_steps=25)
        if not replay:  # every step launched from Python (the env captured its step when it was built)
            env.sim.capture = lambda fn: None
            env._graph = None
        gen = torch.Generator().manual_seed(0)
        out = []
        for _ in range(40):  # falls, contacts and a truncation reset at step 25
            obs, rew, term, trunc, info = env.step(torch.rand(4, 8, generator=gen) * 2 - 1)
            out.append(torch.cat([obs, rew[:, None], trunc[:, None].float(), info["final_obs"]], 1).clone())
        assert (env._graph is not None) == replay
        runs.append(torch.stack(out))
    assert torch.equal(runs[0], runs[1])


@pytest.mark.parametrize("module, name", [("warpgym.envs.robots", "LocomotionVecEnv"),
                                          ("warpgym.envs.suite", "SuiteVecEnv")])
def test_an_env_whose_constructor_raised_still_closes(module, name):
    """A wrong kwarg raises in the constructor, before the renderer is set; Gymnasium's ``VectorEnv.__del__`` then
    closes the half-built object (gymnasium 1.2.2), which once raised AttributeError on ``_view``."""
    import importlib

    cls = getattr(importlib.import_module(module), name)
    env = cls.__new__(cls)  # what a constructor that raised at its first line leaves
    env.close()
    assert env.closed
