"""Learner adapters: each trains a few iterations, counts the same episodes warpgym does, and
hands the learner warpgym's own buffers wherever the learner allows it."""

import numpy as np
import pytest
import torch

LEARNERS = {"rsl_rl": "rsl_rl", "skrl": "skrl", "rl_games": "rl_games", "sb3": "stable_baselines3"}


def learner_returns(name: str, learner) -> list[float]:
    """The episode returns the learner computed itself, from the rewards and dones it was handed."""
    if name == "rsl_rl":
        return list(learner.logger.rewbuffer)
    if name == "skrl":
        return np.asarray(list(learner._track_rewards)).reshape(-1).tolist()
    if name == "sb3":
        return [e["r"] for e in learner.ep_info_buffer]
    return [float(np.asarray(learner.game_rewards.get_mean()).reshape(-1)[0])]  # rl_games keeps a running mean only


@pytest.mark.parametrize("task", ["Ant", "Hopper-v5"])
@pytest.mark.parametrize("name", list(LEARNERS))
def test_each_learner_trains_and_counts_warpgym_episodes(name, task, tmp_path):
    """warpgym's Ant and one of Gymnasium's suite (its observation and action sizes from the task)."""
    pytest.importorskip(LEARNERS[name])
    from warpgym.cli import train_with

    from agents.logger import read_metrics

    args = train_with.parse_args([name, "--task", task, "--num-envs", "4", "--iterations", "3", "--device", "cpu",
                                  "--episode-length", "16", "--run-dir", str(tmp_path), "--no-plots", "--no-compile"])
    args.keep_returns = True
    assert train_with.main(args=args) == 0
    ours = args.episode_log.returns
    theirs = learner_returns(name, args.learner_object)
    assert len(ours) >= 12, f"only {len(ours)} episodes ended"
    if name == "rl_games":  # fewer episodes than its window: its mean is the mean of all of them
        np.testing.assert_allclose(theirs[0], np.mean(ours), rtol=1e-4)
    else:
        assert len(theirs) == min(len(ours), 100)
        np.testing.assert_allclose(theirs, ours[-len(theirs):], rtol=1e-4, atol=1e-4)
    rows = read_metrics(str(tmp_path))
    assert len(rows) >= 3 and rows[-1]["samples"] == 4 * args.episode_log.steps
    assert any("return" in r for r in rows)


def _outputs(name: str, adapter, actions: torch.Tensor) -> dict:
    """What one step hands the learner, by the names of the adapter's SHARED table."""
    if name == "rsl_rl":
        obs, rew, done, extras = adapter.step(actions)
        return {"obs": obs["policy"], "reward": rew, "done": done, "time_outs": extras["time_outs"]}
    if name == "skrl":
        obs, rew, term, trunc, _ = adapter.step(actions)
        return {"obs": obs, "reward": rew, "terminated": term, "truncated": trunc}
    if name == "rl_games":
        obs, rew, done, infos = adapter.step(actions)
        return {"obs": obs, "reward": rew, "done": done, "time_outs": infos["time_outs"]}
    adapter.step_async(actions.numpy())
    obs, rew, done, _ = adapter.step_wait()
    return {"obs": obs, "reward": rew, "done": done}


@pytest.mark.parametrize("name", list(LEARNERS))
def test_adapters_hand_out_warpgym_buffers_or_say_why_not(name, ant_env):
    pytest.importorskip(LEARNERS[name])
    module = {"rsl_rl": "rsl_rl", "skrl": "skrl", "rl_games": "rl_games", "sb3": "sb3"}[name]
    cls = {"rsl_rl": "RslRlVecEnv", "skrl": "SkrlVecEnv", "rl_games": "RlGamesVecEnv", "sb3": "Sb3VecEnv"}[name]
    adapter_cls = getattr(__import__(f"warpgym.wrappers.{module}", fromlist=[cls]), cls)
    adapter = adapter_cls(ant_env)
    if name == "skrl":
        adapter.reset()
    elif name in ("rsl_rl",):
        adapter.get_observations()
    else:
        adapter.reset()
    out = _outputs(name, adapter, torch.zeros(ant_env.num_envs, ant_env.num_actions))
    warpgym = {"obs": ant_env.obs, "reward": ant_env.reward, "done": ant_env.info["_final_obs"],
               "time_outs": ant_env.info["time_outs"], "terminated": ant_env.terminated, "truncated": ant_env.truncated}
    assert set(out) == set(adapter_cls.SHARED)
    for key, shared in adapter_cls.SHARED.items():
        if shared:
            assert isinstance(out[key], torch.Tensor) and out[key].data_ptr() == warpgym[key].data_ptr(), key
        else:
            assert adapter_cls.WHY_COPIED.get(key), f"{cls} copies {key} without saying why"
            if isinstance(out[key], torch.Tensor):
                assert out[key].data_ptr() != warpgym[key].data_ptr()
        np.testing.assert_array_equal(np.asarray(out[key]).reshape(-1), warpgym[key].numpy().reshape(-1))
    if not adapter_cls.SHARED["obs"]:  # the copy the learner acted on survives the next step
        kept = out["obs"]
        before = np.array(kept, copy=True)
        _outputs(name, adapter, torch.rand(ant_env.num_envs, ant_env.num_actions) * 2 - 1)
        np.testing.assert_array_equal(np.asarray(kept), before)
        assert not np.array_equal(before, ant_env.obs.numpy())


def test_gymnasium_conventions(ant_env):
    """numpy actions are taken, the single env passes Gymnasium's checker, and Gymnasium's own
    episode statistics agree with warpgym's through the numpy vector env."""
    import gymnasium as gym
    from gymnasium.utils.env_checker import check_env
    from gymnasium.wrappers.vector import RecordEpisodeStatistics

    import warpgym  # noqa: F401
    from warpgym.envs import LocomotionVecEnv
    from warpgym.wrappers.numpy_vec import NumpyVecEnv

    obs, *_ = ant_env.step(np.zeros((ant_env.num_envs, ant_env.num_actions), np.float64))
    assert isinstance(obs, torch.Tensor)
    with pytest.raises(ValueError, match="shape"):
        ant_env.step(np.zeros((ant_env.num_envs + 1, ant_env.num_actions), np.float32))

    single = gym.make("warpgym/Ant-v0")
    check_env(single.unwrapped, skip_render_check=True)
    assert ant_env.metadata["autoreset_mode"] == gym.vector.AutoresetMode.SAME_STEP

    env = RecordEpisodeStatistics(NumpyVecEnv(LocomotionVecEnv("Ant", num_envs=3, device="cpu", seed=1,
                                                               max_episode_steps=8)), stats_key="gym_episode")
    env.reset(seed=3)
    # Gymnasium before 1.4 counts every vector env as next-step autoreset there: the first step of each
    # later episode is dropped from its return and length (warpgym's info["episode"] is right in both)
    drops_first_step = tuple(int(p) for p in gym.__version__.split(".")[:2]) < (1, 4)
    rng = np.random.default_rng(0)
    seen = 0
    first = np.zeros(3)  # each env's reward in the first step of its running episode, if a later one
    restarted, later = np.zeros(3, bool), np.zeros(3, bool)
    for _ in range(20):
        _, reward, term, trunc, info = env.step(rng.uniform(-1, 1, (3, env.single_action_space.shape[0])))
        assert isinstance(reward, np.ndarray) and reward.dtype == np.float64
        first = np.where(restarted, reward, first)
        if "gym_episode" in info:
            mask = info["_gym_episode"]
            dropped = later & drops_first_step
            np.testing.assert_allclose(info["gym_episode"]["r"][mask],
                                       (info["episode"]["r"] - np.where(dropped, first, 0.0))[mask], rtol=1e-5)
            np.testing.assert_array_equal(info["gym_episode"]["l"][mask], (info["episode"]["l"] - dropped)[mask])
            seen += int(mask.sum())
        restarted = term | trunc
        later |= restarted
    assert seen >= 6


def test_rsl_rl_logs_a_rough_tasks_curriculum_as_isaac_lab_and_mjlab_do():
    pytest.importorskip("rsl_rl")
    from warpgym.envs.legged import LeggedVecEnv
    from warpgym.wrappers.rsl_rl import RslRlVecEnv

    env = LeggedVecEnv("Go1VelocityRough-v0", num_envs=2, device="cpu", seed=0)
    adapter = RslRlVecEnv(env)
    adapter.get_observations()
    *_, extras = adapter.step(torch.zeros(2, env.num_actions))
    # rsl_rl's runner logs extras["log"] every iteration, keys with a slash as they are
    level = extras["log"]["Curriculum/terrain_level"]
    assert float(level) == pytest.approx(float(env.info["terrain_level"].float().mean()))
    assert set(extras) == {"time_outs", "log"}


def test_rsl_rl_gives_a_legged_tasks_critic_its_own_observation():
    """The critic group is the task's critic observation, copied by turns as the policy's is: what rsl_rl holds from
    one step is still that step's after the next one."""
    pytest.importorskip("rsl_rl")
    from warpgym.envs.legged import LeggedVecEnv
    from warpgym.wrappers.rsl_rl import RslRlVecEnv

    env = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=2, device="cpu", seed=0)
    adapter = RslRlVecEnv(env)
    first = adapter.get_observations()
    assert first["policy"].shape == (2, env.num_obs) and first["critic"].shape == (2, env.num_critic_obs)
    assert env.num_critic_obs > env.num_obs
    torch.testing.assert_close(first["critic"], env.info["critic_obs"])
    kept = first["critic"].clone()
    obs, *_ = adapter.step(torch.full((2, env.num_actions), 0.5))
    torch.testing.assert_close(obs["critic"], env.info["critic_obs"])
    assert obs["critic"].data_ptr() != env.info["critic_obs"].data_ptr()  # a copy, not the buffer the env rewrites
    torch.testing.assert_close(first["critic"], kept)  # the first step's copy outlived the second step
    assert not torch.equal(obs["critic"], kept)


def test_rsl_rl_trains_a_legged_task_on_mjlabs_settings(tmp_path):
    """`warpgym train-with rsl_rl` on the Go1: the actor reads the policy's 48 values, the critic its own 72, and the
    metrics carry the tracking errors (the legged episodes have no forward speed)."""
    pytest.importorskip("rsl_rl")
    from warpgym.cli import train_with

    from agents.logger import read_metrics

    args = train_with.parse_args(["rsl_rl", "--task", "Go1VelocityFlat-v0", "--num-envs", "4", "--iterations", "2",
                                  "--device", "cpu", "--episode-length", "12", "--run-dir", str(tmp_path), "--no-plots"])
    args.keep_returns = True
    assert train_with.main(args=args) == 0
    runner = args.learner_object
    sizes = {name: next(m for m in model.modules() if isinstance(m, torch.nn.Linear)).in_features
             for name, model in (("actor", runner.alg.actor), ("critic", runner.alg.critic))}
    assert sizes == {"actor": 48, "critic": 72}
    ours = args.episode_log.returns
    assert len(ours) >= 4
    np.testing.assert_allclose(learner_returns("rsl_rl", runner), ours[-min(len(ours), 100):], rtol=1e-4, atol=1e-4)
    rows = [r for r in read_metrics(str(tmp_path)) if "return" in r]
    assert rows and all("error_vel_xy" in r and "error_vel_yaw" in r and "speed" not in r for r in rows)


def test_episode_log_reports_what_a_task_has():
    """Reacher-v5's episodes carry no forward speed: the rows hold return and length without one (they failed on the
    missing speed before)."""
    from warpgym.envs import make_vec_env
    from warpgym.wrappers.common import EpisodeLog

    env = make_vec_env("Reacher-v5", num_envs=2, device="cpu", max_episode_steps=3)
    rows = []
    log = EpisodeLog(env, every=3, sink=rows.append)
    env.reset(seed=0)
    for _ in range(6):
        *_, info = env.step(torch.zeros(2, 2))
        log.after_step(info)
    assert len(rows) == 2 and all(r["episodes"] == 2 and r["length"] == 3 for r in rows)
    assert all("return" in r and "speed" not in r for r in rows)
