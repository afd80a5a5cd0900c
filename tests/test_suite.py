"""Gymnasium's MuJoCo suite against Gymnasium's own envs (CPU): the model each task simulates is
MuJoCo's compile of the file, one step from the same states gives the same observation, reward,
reward terms and termination, and random-action episodes have the same distributions."""

import os
import re

import gymnasium as gym
import numpy as np
import pytest
import torch

from conftest import DEVICE
from warpgym.native.suite import (
    compare_steps,
    gymnasium_env,
    gymnasium_episodes,
    gymnasium_samples,
    ks_two_sample,
    warpgym_episodes,
)
from warpgym.envs.suite import SuiteVecEnv
from warpgym.sim.gym_model import PHYSICS_FIELDS, compile_model, field_value, model_differences
from warpgym.tasks.suite import SUITE

NAMES = list(SUITE)
# Largest relative step differences allowed (|warpgym - Gymnasium| / (1 + |Gymnasium|)): float32
# against float64 over one env step (2-5 physics steps). HalfCheetah's joint speeds differ most: a
# contact that starts within float32's reach of the margin in one of its five Euler steps gave 3.5e-4
# in 1 of 128 states (benchmarks/physics/conformance.py); every other task stays below 8e-5. The humanoids
# solve their contacts with Newton's method where the file asks for PGS (docs/tasks.md): the contact
# forces in their observation (its last 78 entries) differ by up to 5e-3 of (1 + force) lying down.
OBS_TOL = 2e-4
OBS_TOL_OF = {"HalfCheetah-v5": 1e-3}
CONTACT_OBS_TOL = {"Humanoid-v5": 2e-2, "HumanoidStandup-v5": 2e-2}
REWARD_TOL = 2e-5
REWARD_TOL_OF = {"Humanoid-v5": 1e-4, "HumanoidStandup-v5": 1e-4}  # their contact cost: PGS against Newton
SAMPLES = dict(episodes=6, steps_apart=5, per_episode=4)  # reset states and states 5, 10, 15 steps in


@pytest.fixture(scope="module")
def suite_envs():
    """One env per task, enough worlds for the step samples, built once."""
    envs = {}

    def get(name):
        if name not in envs:
            envs[name] = SuiteVecEnv(name, num_envs=SAMPLES["episodes"] * SAMPLES["per_episode"], device=DEVICE,
                                     seed=0)
        return envs[name]

    return get


@pytest.mark.parametrize("name", NAMES)
def test_the_simulated_model_is_mujocos_compile_of_the_file(name, suite_envs):
    env = suite_envs(name)
    mujoco_compile = gymnasium_env(name).unwrapped.model  # Gymnasium's own compile of its file
    assert model_differences(mujoco_compile, compile_model(SUITE[name].xml_file).mjm) == {}
    # and MuJoCo Warp holds those numbers (float32) in the model it steps
    m, gaps = env.sim.m, {}
    for field in PHYSICS_FIELDS:
        obj = m
        for part in field.split("."):
            obj = getattr(obj, part, None)
        if obj is None:
            continue
        ours = np.asarray(obj.numpy() if hasattr(obj, "numpy") else obj, np.float64)
        theirs = field_value(mujoco_compile, field).astype(np.float64)
        assert ours.size == theirs.size, field
        ours = ours.reshape(theirs.shape)
        finite = np.isfinite(theirs)
        assert np.array_equal(np.isfinite(ours), finite), field
        gap = np.abs(ours - theirs)[finite] / np.maximum(1.0, np.abs(theirs[finite]))
        gaps[field] = float(gap.max()) if gap.size else 0.0
    assert len(gaps) >= len(PHYSICS_FIELDS) - 3, sorted(set(PHYSICS_FIELDS) - set(gaps))
    assert max(gaps.values()) < 1e-6, {k: v for k, v in gaps.items() if v >= 1e-6}


def test_only_the_humanoids_solver_is_substituted():
    changed = {name: compile_model(task.xml_file).substitutions for name, task in SUITE.items()}
    assert {n for n, s in changed.items() if s} == {"Humanoid-v5", "HumanoidStandup-v5"}
    assert all("PGS -> Newton" in s[0] for s in changed.values() if s)


@pytest.mark.parametrize("name", NAMES)
def test_one_step_matches_gymnasium_from_the_same_states(name, suite_envs):
    samples = gymnasium_samples(SUITE[name], **SAMPLES)
    assert sum(s.after_reset for s in samples) == SAMPLES["episodes"] and len(samples) > SAMPLES["episodes"]
    gaps = compare_steps(suite_envs(name), samples)
    print(f"{name}: {gaps}")
    contact = 78 if name in CONTACT_OBS_TOL else 0
    body = gaps.obs_by_entry[: len(gaps.obs_by_entry) - contact]
    assert body.max() < OBS_TOL_OF.get(name, OBS_TOL), (gaps, int(body.argmax()))
    if contact:
        assert gaps.obs_by_entry[-contact:].max() < CONTACT_OBS_TOL[name], gaps
    assert gaps.reward < REWARD_TOL_OF.get(name, REWARD_TOL), gaps
    assert set(gaps.terms) == set(SUITE[name].info_keys)  # every key warpgym reports, Gymnasium's info has
    assert max(gaps.terms.values()) < REWARD_TOL_OF.get(name, REWARD_TOL), gaps.terms
    assert gaps.terminated_mismatches == 0, gaps


@pytest.mark.parametrize("change, field", [({"ctrl_cost_weight": 2e-3}, "reward"), ({"frame_skip": 5}, "obs"),
                                           ({"healthy_reward": 0.5}, "reward"),
                                           ({"healthy_state_range": (-1.0, 1.0)}, "terminated_mismatches"),
                                           ({"exclude_current_positions_from_observation": False}, "shape")])
def test_a_wrong_definition_fails_the_comparison(change, field):
    samples = gymnasium_samples(SUITE["Hopper-v5"], episodes=2, steps_apart=5, per_episode=3)
    env = SuiteVecEnv(SUITE["Hopper-v5"].replace(**change), num_envs=len(samples), device=DEVICE)
    if field == "shape":
        with pytest.raises(ValueError, match="broadcast|shape"):
            compare_steps(env, samples)
        return
    gaps = compare_steps(env, samples)
    if field == "terminated_mismatches":
        assert gaps.terminated_mismatches > 0, gaps
        return
    assert getattr(gaps, field) > 10 * (OBS_TOL if field == "obs" else REWARD_TOL), gaps


def test_the_pendulum_observation_term_is_checked():
    """An observation of the wrong quantity, not only of the wrong size, fails: InvertedDoublePendulum's
    last entry is the cart's constraint force, which a reset state reads as 0 and a state at the rail's
    end does not."""
    task = SUITE["InvertedDoublePendulum-v5"]
    samples = gymnasium_samples(task, episodes=3, steps_apart=1, per_episode=3)
    env = SuiteVecEnv(task, num_envs=len(samples), device=DEVICE)
    for s in samples:
        s.obs = s.obs.copy()
        s.obs[-1] += 0.5
    assert compare_steps(env, samples).worst_obs_entry == task.observation_size(env.sim) - 1


@pytest.mark.parametrize("name", NAMES)
def test_random_action_episodes_have_gymnasiums_distribution(name):
    """Two-sample Kolmogorov-Smirnov tests of return and length over 32 uniform-random-action
    episodes each, cut at 120 steps on both sides (the full episodes: benchmarks/physics/conformance.py)."""
    task = SUITE[name].replace(episode_length=min(SUITE[name].episode_length, 120))
    returns, lengths = gymnasium_episodes(task, 32, seed=0)
    mine_r, mine_l = warpgym_episodes(SuiteVecEnv(task, num_envs=32, device=DEVICE, seed=0), seed=0)
    ks_r, ks_l = ks_two_sample(returns, mine_r), ks_two_sample(lengths, mine_l)
    print(f"{name}: return {returns.mean():.2f} vs {mine_r.mean():.2f} (KS {ks_r[0]:.3f}, p {ks_r[1]:.3f}); "
          f"length {lengths.mean():.1f} vs {mine_l.mean():.1f} (KS {ks_l[0]:.3f}, p {ks_l[1]:.3f})")
    assert ks_r[1] > 1e-3 and ks_l[1] > 1e-3


def test_ks_test_tells_different_distributions_apart():
    rng = np.random.default_rng(0)
    same = ks_two_sample(rng.normal(size=200), rng.normal(size=200))
    shifted = ks_two_sample(rng.normal(size=200), rng.normal(0.5, 1.0, size=200))
    assert same[1] > 0.05 and shifted[1] < 1e-3


def test_gymnasium_ids_spaces_and_time_limits():
    for name, task in SUITE.items():
        spec = gym.spec(f"warpgym/{name}")
        assert spec.max_episode_steps == gym.spec(name).max_episode_steps == task.episode_length
    env = gym.make("warpgym/Reacher-v5")
    theirs = gym.make("Reacher-v5")
    assert env.observation_space.shape == theirs.observation_space.shape
    assert np.array_equal(env.action_space.low, theirs.action_space.low)
    assert np.array_equal(env.action_space.high, theirs.action_space.high)
    obs, _ = env.reset(seed=0)
    for t in range(60):
        obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
        if terminated or truncated:
            break
    assert (t + 1, terminated, truncated) == (50, False, True)
    assert set(info) >= {"reward_dist", "reward_ctrl", "episode"} and info["episode"]["l"] == 50


def test_vector_env_autoresets_in_the_step_with_final_obs(suite_envs):
    env = suite_envs("Hopper-v5")
    env.reset(seed=3)
    ended = torch.zeros(env.num_envs, dtype=torch.bool)
    for _ in range(200):
        obs, reward, terminated, truncated, info = env.step(torch.ones(env.num_envs, env.num_actions))
        done = terminated | truncated
        if done.any():
            # the final observation is the fallen hopper's; the returned one a fresh start near the reset pose
            assert torch.all(info["final_obs"][done][:, 0] != obs[done][:, 0])
            assert torch.all((obs[done][:, 0] - 1.25).abs() < 0.01)  # qpos[1], the torso height at reset
            assert torch.all(info["episode"]["l"][done] > 0)
            ended |= done
    assert ended.any()


def test_bad_input_names_the_value_and_the_fix():
    with pytest.raises(ValueError, match=r"unknown task 'Hoper-v5'.*Hopper-v5"):
        SuiteVecEnv("Hoper-v5")
    with pytest.raises(ValueError, match=r"no argument\(s\) \['ctrl_cost'\].*ctrl_cost_weight"):
        SuiteVecEnv("Hopper-v5", ctrl_cost=0.1)
    with pytest.raises(ValueError, match="healthy_z_range"):
        SuiteVecEnv("Hopper-v5", healthy_z_range=(2.0, 1.0))
    with pytest.raises(FileNotFoundError, match="xml_file='nope.xml'.*gymnasium ships"):
        SuiteVecEnv("Hopper-v5", xml_file="nope.xml")
    with pytest.raises(ValueError, match=r"actions has shape"):
        env = gym.make_vec("warpgym/InvertedPendulum-v5", num_envs=2, device=DEVICE)
        env.step(torch.zeros(2, 3))


@pytest.mark.slow
def test_inverted_pendulum_trains_to_900_in_gymnasiums_own_env(tmp_path, capsys):
    """``warpgym train --task InvertedPendulum-v5`` on the CPU, then ``warpgym eval``: the deterministic
    policy over 10 episodes (seeds 0 and 1) of ``gymnasium.make("InvertedPendulum-v5")`` (float64 MuJoCo),
    beside its return in warpgym's env."""
    import json

    from warpgym.cli import eval as eval_command, train

    run = str(tmp_path / "ip")
    assert train.main(["--task", "InvertedPendulum-v5", "--device", DEVICE, "--max-iterations", "60", "--run-dir",
                       run, "--no-plots", "--seed", "1"]) == 0
    out = str(tmp_path / "eval.json")
    assert eval_command.main([run, "--episodes", "5", "--seeds", "0", "1", "--json", out, "--nudge", "1e-9"]) == 0
    print(capsys.readouterr().out[-600:])
    result = json.load(open(out))
    assert result["episodes"] == 10 and [s["seed"] for s in result["per_seed"]] == [0, 1]
    assert result["gymnasium_return"] >= 900, result
    assert "normalizer_mean" not in result  # the preset has no normaliser whose statistics it could report
    assert 0.95 <= result["gymnasium_over_warpgym"] <= 1.05, result
    assert result["nudge"] == 1e-9 and 0.95 <= result["gymnasium_over_gymnasium_nudged"] <= 1.05, result
    for env in ("gymnasium", "warpgym"):  # the episodes one by one, the same starts in the same order
        assert len(result[f"{env}_returns"]) == len(result[f"{env}_lengths"]) == 10, result
        assert np.mean(result[f"{env}_returns"]) == pytest.approx(result[f"{env}_return"], rel=1e-9)
        assert np.mean(result[f"{env}_lengths"]) == pytest.approx(result[f"{env}_length"], rel=1e-9)
    for env in ("gymnasium", "warpgym"):  # the one term, survival, is the whole return
        assert result[f"{env}_terms"]["reward_survive"] == pytest.approx(result[f"{env}_return"], rel=1e-6)
    evals = [json.loads(line) for line in open(os.path.join(run, "metrics.jsonl")) if "eval/return" in line]
    assert evals and all(r["eval/reward_survive"] == pytest.approx(r["eval/return"], rel=1e-6) for r in evals)
    # in v4 a fall's step still pays 1: v4's return is v5's plus at most 1, the same episodes otherwise
    assert eval_command.main([run, "--episodes", "3", "--seeds", "0", "--json", out, "--env-version", "4"]) == 0
    result = json.load(open(out))
    assert 0.0 <= result["v4_return"] - result["gymnasium_return"] <= 1.0 + 1e-9, result
    assert result["v4_length"] == result["gymnasium_length"], result
    # the preset trains without an observation normaliser: nothing to swap, said before anything is built
    with pytest.raises(SystemExit) as refused:
        eval_command.main([run, "--normalizer-from", run])
    assert refused.value.code == 2 and "trained without an observation normaliser" in capsys.readouterr().err
    pytest.importorskip("PIL")
    from PIL import Image

    from warpgym.cli import play

    gif = str(tmp_path / "ip.gif")
    assert play.main([run, "--gif", gif, "--steps", "50", "--device", DEVICE]) == 0
    with Image.open(gif) as im:  # 50 steps of 40 ms in real time, however many frames a GIF merges
        shown = 0
        for i in range(im.n_frames):
            im.seek(i)
            shown += im.info["duration"]
    assert shown == 51 * 40


def test_how_much_of_a_return_holds_reads_alike_for_rewards_and_costs():
    from warpgym.cli.eval import holds

    assert holds(900.0, 1000.0) == pytest.approx(0.9) and holds(1100.0, 1000.0) == pytest.approx(1.1)
    # Reacher's cost: -4.3 in Gymnasium's env for -3.24 in warpgym's is worse, so below 1
    assert holds(-4.3, -3.24) == pytest.approx(3.24 / 4.3) and holds(-3.0, -3.24) > 1.0
    assert holds(5.0, -1.0) == 1.0 and holds(-1.0, 0.0) == 0.0


def test_eval_refuses_gymnasiums_own_flags_for_a_robot_and_a_v4_it_cannot_play(tmp_path, capsys):
    import glob

    from agents.checkpoint import load, save_atomic
    from warpgym.cli import eval as eval_command

    # warpgym's own Ant is scored in native MuJoCo (tests/test_train.py): Gymnasium's v4 is no place for it
    policy = sorted(glob.glob(os.path.join(os.path.dirname(__file__), "data", "ant*.pt")))[0]
    with pytest.raises(SystemExit) as refused:  # one line and status 2, as for any wrong flag
        eval_command.main([policy, "--env-version", "4"])
    assert refused.value.code == 2 and "--env-version 4: Gymnasium's env only" in capsys.readouterr().err
    # a suite task whose v4 is laid out otherwise: refused before anything is built, naming the tasks that play
    ckpt = load(policy, torch.device("cpu"))
    ckpt["config"]["env_args"]["task"] = "Ant-v5"
    save_atomic(ckpt, str(tmp_path / "ant_v5.pt"))
    with pytest.raises(SystemExit) as refused:
        eval_command.main([str(tmp_path / "ant_v5.pt"), "--env-version", "4"])
    assert refused.value.code == 2
    assert re.search(r"--env-version 4: Ant-v5's v4 observation .*Reacher-v5", capsys.readouterr().err)


def test_suite_training_refuses_the_robots_physics_flags(capsys):
    from warpgym.cli import train

    with pytest.raises(SystemExit) as done:
        train.main(["--task", "Hopper-v5", "--device", DEVICE, "--substeps", "2", "--max-iterations", "1"])
    assert done.value.code == 2 and "--substeps / --physics" in capsys.readouterr().err
    # training clips film the robots only (the registry's training_clips): refused before anything is built
    with pytest.raises(SystemExit) as done:
        train.parse_args(["--task", "hopper-v5", "--video"])
    assert done.value.code == 2 and "--video: training clips draw warpgym's own robots only" in capsys.readouterr().err


def test_learner_adapters_and_elegantrl_take_the_tasks_sizes():
    """Each adapter built on a suite task reports its observation and action sizes and steps it."""
    from warpgym.envs import make_vec_env
    from warpgym.envs.elegantrl import IsaacVecEnv
    from warpgym.wrappers.rsl_rl import RslRlVecEnv
    from warpgym.wrappers.sb3 import Sb3VecEnv

    env = make_vec_env("Reacher-v5", num_envs=4, device=DEVICE)
    assert env.unit_actions and (env.num_obs, env.num_actions) == (10, 2)
    assert np.array_equal(env.single_action_space.low, [-1.0, -1.0])
    rsl = RslRlVecEnv(env)
    assert (rsl.num_actions, rsl.max_episode_length, rsl.cfg["task"]) == (2, 50, "Reacher-v5")
    sb3 = Sb3VecEnv(env)
    obs = sb3.reset()
    assert obs.shape == (4, 10)
    sb3.step_async(np.ones((4, 2), np.float32) * 5.0)  # clipped to 1, the top of the control range
    _, reward, _, infos = sb3.step_wait()
    # Gymnasium's control cost of ctrl = (1, 1) at weight 1: -2
    assert np.allclose([i.get("reward_ctrl", env.info["reward_ctrl"][k].item()) for k, i in enumerate(infos)], -2.0)
    erl = IsaacVecEnv("Hopper-v5", env_num=3, device_id=-1)
    assert (erl.state_dim, erl.action_dim, erl.max_step) == (11, 3, 1000)
    state = erl.reset()
    state, reward, done, _ = erl.step(torch.zeros(3, 3))
    assert state.shape == (3, 11) and reward.shape == (3,)


def test_plane_capsule_contact_frames_are_mujocos_and_mujoco_warps_own_still_differ():
    """A capsule 80 degrees from the floor: MuJoCo's first contact tangent is its axis projected onto the
    floor; warpgym's correction (warpgym/sim/mjw_internals.py) gives the same. MuJoCo Warp's own frame
    still differs: when this part fails, MuJoCo Warp has been fixed and the correction can go."""
    import mujoco
    import mujoco_warp as mjw
    import warp as wp

    from warpgym.sim.mjw_internals import mujoco_contact_frames

    xml = """<mujoco><worldbody><geom type="plane" size="5 5 0.1"/>
      <body pos="0 0 0.24" euler="0 10 30"><freejoint/><geom type="capsule" size="0.05 0.2" condim="3"/></body>
      </worldbody></mujoco>"""
    mjm = mujoco.MjModel.from_xml_string(xml)
    mjd = mujoco.MjData(mjm)
    mujoco.mj_forward(mjm, mjd)
    assert mjd.ncon >= 1
    frames = {}
    with wp.ScopedDevice(DEVICE):
        m = mjw.put_model(mjm)
        for corrected in (True, False):
            d = mjw.put_data(mjm, mjd, nconmax=8, njmax=32)
            with mujoco_contact_frames(corrected):
                mjw.forward(m, d)
            frames[corrected] = d.contact.frame.numpy()[: int(d.nacon.numpy()[0])].reshape(-1, 9)
    theirs = mjd.contact.frame[: mjd.ncon]
    assert np.allclose(frames[True], theirs, atol=1e-5), (frames[True], theirs)
    assert not np.allclose(frames[False][:, 3:6], theirs[:, 3:6], atol=1e-2)


def test_a_model_mujoco_warp_cannot_run_fails_in_one_line_naming_the_file(monkeypatch):
    """MuJoCo Warp refuses some features at put_model (plugins, some flex collisions); the env says which
    file, what MuJoCo Warp said, and the way out."""
    import mujoco_warp

    def refuse(mjm):
        raise NotImplementedError("Body plugins not supported.")

    monkeypatch.setattr(mujoco_warp, "put_model", refuse)
    with pytest.raises(NotImplementedError) as caught:
        SuiteVecEnv("Hopper-v5", num_envs=1, device=DEVICE)
    message = str(caught.value)
    assert "\n" not in message and "hopper.xml" in message and "Body plugins not supported" in message
    assert "pass its path" in message


def test_render_draws_the_worlds_as_gymnasiums_own_renderer_does():
    """``render_mode="rgb_array"``: the frame of a world is Gymnasium's own frame of the same state."""
    pytest.importorskip("PIL")
    import mujoco

    from warpgym.media.render import RendererUnavailable, probe_renderer

    try:
        probe_renderer()
    except RendererUnavailable as e:
        pytest.skip(str(e))
    env = gym.make_vec("warpgym/Hopper-v5", num_envs=3, device=DEVICE, render_mode="rgb_array", render_robots=2,
                       render_size=(96, 64))
    env.reset(seed=0)
    for _ in range(4):
        env.step(torch.rand(3, 3) * 2 - 1)
    frames = env.render()
    assert len(frames) == 2 and frames[0].shape == (64, 96, 3) and frames[0].dtype == np.uint8
    theirs = gym.make("Hopper-v5", render_mode="rgb_array", width=96, height=64)
    theirs.reset(seed=0)
    for i in range(2):
        u = theirs.unwrapped
        u.data.qpos[:], u.data.qvel[:] = env.sim.dof_pos[i].numpy(), env.sim.dof_vel[i].numpy()
        mujoco.mj_forward(u.model, u.data)
        assert np.array_equal(theirs.render(), frames[i])
    assert not np.array_equal(frames[0], frames[1])  # two worlds, two states
    theirs.close()
    env.close()


def test_tensor_api_views_of_the_suites_worlds(suite_envs):
    env = suite_envs("Ant-v5")
    sim = env.sim
    env.reset(seed=0)
    assert sim.root_pose.shape == (env.num_envs, 7) and sim.root_vel.shape == (env.num_envs, 6)
    assert sim.dof_pos.data_ptr() == sim.root_pose.data_ptr()  # views of MuJoCo Warp's qpos, no copies
    qpos, qvel = sim.dof_pos.clone(), sim.dof_vel.clone()
    qpos[1, 2] = 0.75  # lift world 1's torso
    sim.set_state(qpos[1:2], qvel[1:2], torch.tensor([1]))
    assert float(sim.root_pose[1, 2]) == pytest.approx(0.75) and float(sim.dof_pos[0, 2]) == float(qpos[0, 2])
    assert float(sim.to_torch(sim.d.qacc_warmstart)[1].abs().sum()) == 0.0
    with pytest.raises(ValueError, match="qpos has shape"):
        sim.set_state(qpos, qvel, torch.tensor([1]))
    with pytest.raises(AttributeError, match="no free root joint.*dof_pos"):
        _ = suite_envs("Hopper-v5").sim.root_pose


def test_bench_times_the_task_step_beside_mujoco_warps_from_the_same_states():
    from warpgym.tasks.registry import task_entry

    row = task_entry("Swimmer-v5").bench("Swimmer-v5", 4, DEVICE, 3, 20, 2, None)
    assert row["env_steps_per_s"] > 0 and row["mjwarp_steps_per_s"] > 0
    assert len(row["env_seconds"]) == len(row["mjwarp_seconds"]) == 2
    assert row["faults"] == {"nan_actions": 0, "diverged_resets": 0, "solver_overflows": 0}


def test_one_action_sequence_ends_where_gymnasiums_does_after_1000_steps(suite_envs):
    """A long-horizon check the one-step gaps cannot make: Swimmer's 1000-step return under a fixed
    swimming stroke (no feedback, so no closed loop to part the float32 and float64 trajectories), from
    Gymnasium's own reset states, agrees with Gymnasium's episode by episode."""
    from warpgym.native.suite import open_loop_returns

    env = suite_envs("Swimmer-v5")
    steps = np.arange(1000)[:, None]
    stroke = 0.9 * np.sin(2 * np.pi * steps / 25.0 + 1.3 * np.arange(2)[None])  # a travelling wave, 1 s
    gym_returns, ours = open_loop_returns(env, stroke, seeds=list(range(6)))
    assert gym_returns.min() > 20.0  # it swims: the check is not of a robot lying still
    np.testing.assert_allclose(ours, gym_returns, rtol=0.01)


def test_a_policy_plays_the_same_episodes_in_both_envs_from_gymnasiums_starts(suite_envs):
    """``warpgym eval``'s pairing: Gymnasium's episodes (their states and first observations) replayed by
    the same feedback policy in warpgym's worlds. Reacher's return is mostly its target's distance, which
    each start draws: the returns spread by more than 10 % over the starts, and paired, the episodes agree
    one by one."""
    from warpgym.native.suite import gymnasium_policy_episodes, warpgym_policy_episodes

    env = suite_envs("Reacher-v5")
    weights = torch.randn(env.num_obs, env.num_actions, generator=torch.Generator().manual_seed(0))

    def act(obs):  # a smooth feedback law on the observation (fingertip-to-target vector included)
        return 0.2 * torch.tanh(obs.to(weights.device) @ weights).to(obs.device)

    starts = []
    gym_returns, gym_lengths = gymnasium_policy_episodes("Reacher-v5", act, 8, seed=0, unit_actions=False,
                                                         starts=starts)
    ours, lengths = warpgym_policy_episodes(env, act, starts)
    np.testing.assert_array_equal(lengths, gym_lengths)
    # float32 against float64 over a 50-step loop: 3e-7 apart on the CPU, 2026-11-25
    np.testing.assert_allclose(ours, gym_returns, rtol=1e-4)
    assert np.std(gym_returns) > 0.1 * abs(np.mean(gym_returns))  # the starts matter: pairing is what agrees


def test_reward_terms_sum_to_the_return_and_agree_episode_by_episode(suite_envs):
    """The reward terms ``warpgym eval`` prints: Gymnasium's info entries summed per episode add up to the
    return (HumanoidStandup pays 1 a step beside them), and warpgym's, over the same episodes, agree with
    Gymnasium's term by term."""
    from warpgym.native.suite import gymnasium_policy_episodes, warpgym_policy_episodes

    weights = torch.randn(400, 17, generator=torch.Generator().manual_seed(1))
    for name, actions, rest_per_step in (("Reacher-v5", 2, 0.0), ("InvertedDoublePendulum-v5", 1, 0.0),
                                         ("HumanoidStandup-v5", 17, 1.0)):
        task = SUITE[name].replace(episode_length=40)

        def act(obs, actions=actions):
            return 0.3 * torch.tanh(obs @ weights[: obs.shape[1], :actions].to(obs.device))

        starts, terms = [], {}
        returns, lengths = gymnasium_policy_episodes(task, act, 3, seed=7, unit_actions=False, starts=starts,
                                                     terms=terms)
        assert set(terms) == set(task.reward_terms()) and len(terms) >= 1
        summed = np.sum([terms[k] for k in terms], axis=0)
        np.testing.assert_allclose(summed + rest_per_step * lengths, returns, rtol=1e-12, atol=1e-9)
        if name == "Reacher-v5":  # the same episodes in warpgym: each term as Gymnasium's, episode by episode
            ours_terms = {}
            ours, _ = warpgym_policy_episodes(suite_envs(name), act, starts, max_steps=40, terms=ours_terms)
            for key in terms:
                np.testing.assert_allclose(ours_terms[key], terms[key], rtol=1e-4, atol=1e-5)
            np.testing.assert_allclose(np.sum([ours_terms[k] for k in terms], axis=0), ours, rtol=1e-5)


def test_a_v5_policy_plays_v4_and_is_paid_v4s_reward():
    """``warpgym eval --env-version 4``: the policy sees the part of v4's observation that is v5's and
    plays the same episodes from the same reset seeds (the same actions: the control terms agree), and
    v4 pays Reacher's distance as it was before each step, which the v5 run's observations give."""
    from warpgym.native.suite import gymnasium_policy_episodes

    weights = torch.randn(10, 2, generator=torch.Generator().manual_seed(0))
    seen = []

    def act(obs):  # feedback on every entry, the fingertip-to-target vector included
        seen.append(obs[0].double().numpy().copy())
        return 0.2 * torch.tanh(obs @ weights)

    v5, v4 = {}, {}
    gymnasium_policy_episodes("Reacher-v5", act, 3, seed=4, unit_actions=False, terms=v5)
    before = -np.linalg.norm(np.array(seen)[:, 8:10], axis=1).reshape(3, 50).sum(axis=1)
    seen.clear()
    gymnasium_policy_episodes("Reacher-v5", act, 3, seed=4, unit_actions=False, terms=v4, version=4)
    assert all(len(o) == 10 for o in seen)
    np.testing.assert_allclose(v4["reward_ctrl"], v5["reward_ctrl"], rtol=1e-9)
    np.testing.assert_allclose(v4["reward_dist"], before, rtol=1e-5)
    assert not np.allclose(v4["reward_dist"], v5["reward_dist"], rtol=1e-3)  # v5 reads it after the step
    with pytest.raises(ValueError, match="Ant-v5 in Gymnasium's v4"):
        gymnasium_policy_episodes("Ant-v5", act, 1, version=4)


def test_nudged_starts_move_every_coordinate_and_nothing_else():
    """``gymnasium_policy_episodes(nudge=...)``: Gymnasium's reset states moved by exactly the nudge in
    every qpos coordinate, the velocities and the first observation as drawn; Reacher's return moves
    with its start, and no further than the move's size suggests."""
    from warpgym.native.suite import gymnasium_policy_episodes

    def act(obs):
        return 0.1 * torch.tanh(obs[:, :2])

    plain, moved = [], []
    r0, _ = gymnasium_policy_episodes("Reacher-v5", act, 3, seed=5, unit_actions=False, starts=plain)
    r1, _ = gymnasium_policy_episodes("Reacher-v5", act, 3, seed=5, unit_actions=False, starts=moved, nudge=1e-6)
    for ((qp0, qv0, _, _), obs0), ((qp1, qv1, _, _), obs1) in zip(plain, moved):
        np.testing.assert_allclose(qp1 - qp0, 1e-6, rtol=1e-6)
        np.testing.assert_array_equal(qv1, qv0)
        np.testing.assert_array_equal(obs1, obs0)
    assert not np.array_equal(r0, r1)
    np.testing.assert_allclose(r1, r0, rtol=1e-4)


def test_a_termination_on_the_last_step_is_truncated_too_as_in_gymnasium():
    """Gymnasium's TimeLimit truncates at the limit whether or not the step terminated: a Hopper unhealthy from
    its first step with a one-step limit is (terminated, truncated) = (True, True) in gymnasium.make and here;
    ``info["time_outs"]`` leaves it out of what a learner bootstraps. An explicit reset clears the flags."""
    kwargs = {"healthy_z_range": (5.0, 10.0)}
    reference = gym.make("Hopper-v5", max_episode_steps=1, **kwargs)
    reference.reset(seed=0)
    _, _, gym_terminated, gym_truncated, _ = reference.step(np.zeros(3))
    env = SuiteVecEnv(SUITE["Hopper-v5"].replace(**kwargs), num_envs=2, device=DEVICE, max_episode_steps=1)
    env.reset(seed=0)
    _, _, terminated, truncated, info = env.step(torch.zeros(2, 3))
    assert (gym_terminated, gym_truncated) == (True, True)
    assert terminated.tolist() == truncated.tolist() == [True, True] and not info["time_outs"].any()
    assert info["episode"]["l"].tolist() == [1, 1]  # recorded by the step that ended it
    env.reset()
    assert not (env.terminated.any() or env.truncated.any() or env.info["time_outs"].any())
    assert env.info["episode"]["l"].tolist() == [1, 1]


def test_inverted_double_pendulums_ceiling_is_half_a_point_over_the_published_figure(suite_envs):
    """docs/benchmarks.md: a step pays at most 9.36 (10 for staying up, less the tip's distance penalty of 0.64 with
    both poles straight over the cart at the origin), so 1000 steps return at most 9360.0, half a point over
    Tianshou's 9359.5; in Gymnasium's env and in warpgym's, from that state, the first step pays exactly that."""
    from benchmarks.targets import REFERENCE

    name = "InvertedDoublePendulum-v5"
    theirs = gymnasium_env(name)
    theirs.reset(seed=0)
    model = theirs.unwrapped.model
    theirs.unwrapped.set_state(np.zeros(model.nq), np.zeros(model.nv))
    _, their_reward, *_ = theirs.step(np.zeros(1))
    theirs.close()
    env = suite_envs(name)
    env.reset(seed=0)
    sim = env.sim
    sim.set_state(torch.zeros_like(sim.dof_pos), torch.zeros_like(sim.dof_vel), torch.arange(env.num_envs))
    _, reward, terminated, _, _ = env.step(torch.zeros(env.num_envs, 1, device=sim.dof_pos.device))
    assert their_reward == pytest.approx(9.36, abs=1e-9)
    np.testing.assert_allclose(np.asarray(torch.as_tensor(reward).cpu()), 9.36, atol=1e-5)
    assert not bool(torch.as_tensor(terminated).any())
    assert 1000 * 9.36 - REFERENCE[name] == pytest.approx(0.5)
