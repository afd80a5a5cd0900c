"""RLlib's PPO (new API stack) trains warpgym through warpgym.wrappers.rllib, whose next-step autoreset
is checked against warpgym's own same-step autoreset and info["final_obs"].

RLlib pins gymnasium 1.2.2: CI runs this file in a second environment with that gymnasium and the
rllib extra (.ci/run); where RLlib is not installed it is skipped."""

import numpy as np
import pytest

pytest.importorskip("ray.rllib")


def test_rllib_ppo_trains_warpgym_and_counts_the_same_episodes(tmp_path):
    from agents.logger import read_metrics
    from warpgym.cli import train_with

    args = train_with.parse_args(["rllib", "--num-envs", "4", "--iterations", "2", "--device", "cpu",
                                  "--episode-length", "16", "--run-dir", str(tmp_path), "--no-plots"])
    args.keep_returns = True
    assert train_with.main(args=args) == 0
    first, last = (r["env_runners"] for r in args.rllib_results)
    ours = args.episode_log.returns
    # 2 iterations x 16 steps of 16-step episodes: every env finishes one episode per iteration
    assert len(ours) == 8 and last["num_episodes_lifetime"] == len(ours)
    assert first["episode_len_max"] == 16  # the first episodes start at warpgym's reset
    assert last["episode_len_max"] == 15 and last["episode_len_min"] == 15  # later ones after the hidden step
    rows = read_metrics(str(tmp_path))
    assert len(rows) == 2 and rows[-1]["samples"] == 4 * 32 and rows[-1]["episodes"] == 4
    assert args.learner_object.iteration == 2  # RLlib's own count of finished training iterations


def test_the_time_limit_ends_an_rllib_run_as_a_time_limit_not_an_error(tmp_path):
    """RLlib's env runner turns the adapter's TimeLimitReached into a bare RuntimeError; the run must still
    end with exit 0 and "time limit", as the other learners' runs do."""
    import json

    from warpgym.cli import train_with

    args = train_with.parse_args(["rllib", "--num-envs", "4", "--iterations", "1000", "--device", "cpu",
                                  "--time-limit", "1", "--run-dir", str(tmp_path), "--no-plots"])
    assert train_with.main(args=args) == 0
    with open(tmp_path / "summary.json") as f:
        summary = json.load(f)
    assert summary["stopped_by"] == "time limit"  # before: RLlib's RuntimeError, exit 1 and a traceback


def test_next_step_autoreset_against_warpgyms_final_obs():
    from gymnasium.vector import AutoresetMode

    from warpgym.envs import LocomotionVecEnv
    from warpgym.wrappers.rllib import RllibVecEnv

    base = LocomotionVecEnv("Ant", num_envs=3, device="cpu", seed=2, max_episode_steps=4)
    env = RllibVecEnv(base)
    assert env.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    obs, _ = env.reset(seed=5)
    assert isinstance(obs, np.ndarray) and obs.shape == (3, base.num_obs)
    rng = np.random.default_rng(0)
    ended = restarted = 0
    restarting = np.zeros(3, bool)
    for _ in range(13):
        actions = rng.uniform(-1, 1, (3, base.num_actions)).astype(np.float32)
        obs, reward, terminated, truncated, info = env.step(actions)
        done = base.info["_final_obs"].numpy()
        assert info == {} and reward.dtype == np.float64 and terminated.dtype == bool
        # the env's last observation where it finished, its current one elsewhere
        np.testing.assert_array_equal(obs[done & ~restarting], base.info["final_obs"].numpy()[done & ~restarting])
        np.testing.assert_array_equal(obs[~done], base.obs.numpy()[~done])
        # the step after a finish starts the next episode: no reward, no flag, zero actions
        assert not (terminated | truncated)[restarting].any() and (reward[restarting] == 0).all()
        if restarting.any():
            np.testing.assert_array_equal(obs[restarting], base.obs.numpy()[restarting])
            assert (base.actions.numpy()[restarting & ~done] == 0).all()  # the actions this step applied
        np.testing.assert_array_equal(reward[~restarting], base.reward.numpy()[~restarting])
        ended += int((terminated | truncated).sum())
        restarted += int(restarting.sum())
        restarting = terminated | truncated
    assert ended >= 6 and restarted >= 6  # 4-step episodes: three rounds of finishes and restarts


def test_registered_creator_builds_the_task_with_rllibs_env_count():
    from warpgym.wrappers.rllib import RLLIB_ENV, register_rllib_env, rllib_env_creator

    assert register_rllib_env() == RLLIB_ENV
    env = rllib_env_creator({"task": "Humanoid", "device": "cpu", "num_envs": 2, "seed": 1})
    assert env.num_envs == 2 and env.single_observation_space.shape == (108,)
    obs, _ = env.reset(seed=0)
    assert isinstance(obs, np.ndarray) and obs.shape == (2, 108)
    assert env.metadata["autoreset_mode"].name == "NEXT_STEP"


def test_two_env_runners_and_two_learners_train_one_policy(tmp_path):
    """--gpus 2: two env runners and two DDP learners as Ray actors (on the CPU here); the rows come
    from RLlib's metrics, with warpgym's forward speed from the ForwardSpeed callback."""
    import math

    from agents.logger import read_metrics
    from warpgym.cli import train_with

    args = train_with.parse_args(["rllib", "--gpus", "2", "--num-envs", "4", "--iterations", "3", "--device", "cpu",
                                  "--episode-length", "12", "--horizon-len", "8", "--run-dir", str(tmp_path),
                                  "--no-plots"])
    assert train_with.main(args=args) == 0
    rows = read_metrics(str(tmp_path))
    assert [r["samples"] for r in rows] == [64, 128, 192]  # 2 runners x 4 envs x 8 steps per iteration
    finished = [r for r in rows if r["episodes"]]
    assert finished and all(math.isfinite(r["speed"]) and r["length"] <= 12 for r in finished)
    assert args.learner_object.learner_group.is_remote  # the learners are actors, not this process


@pytest.mark.parametrize("gpus", [2, 4, 8])
def test_each_gpu_gets_one_runner_and_one_learner_however_ray_places_them(gpus):
    """Ray places the runners first, then the learners, each wherever its share fits. The shares leave it one
    choice: a runner per GPU (two do not fit in one) and a learner beside each (it fits beside one runner, two
    do not). Halves, as before, let two DDP learners share a GPU, which NCCL refuses; runners set apart from the
    GPUs share half of them."""
    from warpgym.cli.rllib_run import gpu_shares

    runner, learner = gpu_shares(gpus, runners=gpus, learners=gpus)
    assert 2 * runner > 1 and runner + learner <= 1 and runner + 2 * learner > 1
    assert gpu_shares(1, runners=8, learners=0) == (0.0625, 0.5)  # 8 runners share half of one GPU
    assert gpu_shares(1, runners=0, learners=0) == (0.0, 1.0)  # one learner in this process, its whole GPU


def test_env_runners_apart_from_gpus_sample_for_one_learner_in_this_process(tmp_path):
    """--env-runners 2 on one GPU's worth (the CPU here): two runner actors, each stepping its own robots,
    and the learner in this process learning from both rollouts."""
    from agents.logger import read_metrics
    from warpgym.cli import train_with

    args = train_with.parse_args(["rllib", "--env-runners", "2", "--num-envs", "4", "--iterations", "2",
                                  "--device", "cpu", "--episode-length", "12", "--horizon-len", "8",
                                  "--run-dir", str(tmp_path), "--no-plots"])
    assert train_with.main(args=args) == 0
    assert [r["samples"] for r in read_metrics(str(tmp_path))] == [64, 128]  # 2 runners x 4 envs x 8 steps
    algo = args.learner_object
    assert not algo.learner_group.is_remote and algo.config.train_batch_size_per_learner == 64
    assert algo.config.num_env_runners == 2 and algo.config.num_envs_per_env_runner == 4


def test_rllibs_runner_overhead_is_timed_around_an_env_that_does_nothing():
    """benchmarks/multi_gpu/rllib_overhead.py: RLlib's sampling loop, not the env, is what it times."""
    from benchmarks.multi_gpu import rllib_overhead

    env = rllib_overhead.null_vector_env(4, 3, 2, episode=5)
    env.reset()
    ends = sum(int(env.step(np.zeros((4, 2), np.float32))[3].sum()) for _ in range(10))
    assert ends == 8  # every env ends an episode every 5 steps, staggered
    row = rllib_overhead.time_runner(8, 3, 2, steps=4, repeats=2, episode=5)
    assert row["runner_samples_per_s"] > 0 and row["runner_ms_per_step"] > row["env_alone_ms_per_step"]
