"""A user's own reward, observation and event terms (tests/user_terms.py, a module outside warpgym): in the step's
tables from Python and from `warpgym train`, computed inside the step as warpgym's own terms are, and a
half-declared term refused in one line that names it."""

import json
import os
import subprocess
import sys

import pytest
import torch

pytestmark = pytest.mark.slow

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def test_a_users_terms_join_the_tasks_tables_and_read_the_step_as_its_own_do():
    import gymnasium as gym

    import warpgym  # noqa: F401  (the ids)
    from tests import user_terms

    envs = gym.make_vec("warpgym/Go1VelocityFlat-v0", num_envs=3, device="cpu", events={"push_robot": None},
                        rewards=user_terms.REWARDS, policy_obs=user_terms.OBSERVATIONS)
    obs, info = envs.reset(seed=0)
    assert obs.shape == (3, 48 + 1)  # the Go1's 48 entries, the user's one after them
    torch.manual_seed(0)
    for _ in range(3):
        obs, reward, terminated, truncated, info = envs.step(torch.rand(3, 12) * 2 - 1)
        # the same rate of change as warpgym's term, at 3x the weight's scale: the term read the step's actions,
        # its parameter and its weight x dt
        assert torch.allclose(info["reward_user_action_rate"], 3.0 * info["reward_action_rate_l2"], rtol=1e-5,
                              atol=1e-9)
        assert float(info["reward_action_rate_l2"].abs().min()) > 0
        # the observation reads the state the step ended in, the base's own height
        root = envs.index.root_body
        heights = envs.sim.to_torch(envs.sim.d.xpos)[:, root, 2]
        assert torch.allclose(obs[:, -1], heights, atol=1e-6)
    total = sum(v for k, v in info.items() if k.startswith("reward_"))
    assert torch.allclose(total, reward, atol=1e-6)
    envs.close()


def test_a_users_event_runs_at_each_reset_after_the_tasks_own():
    """The user's reset event sets the base's upward speed within its range after every reset, the task's reset
    pose still drawn; a world that goes on keeps falling under gravity instead."""
    from tests import user_terms
    from warpgym.envs.legged import LeggedVecEnv

    env = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=16, device="cpu", seed=3, events=user_terms.EVENTS)
    plain = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=16, device="cpu", seed=3)
    assert list(env.task.events)[-1] == "lift" and list(env.task.events)[:-1] == list(plain.task.events)
    up = env.index.root_dof + 2
    for seed in (0, 1):
        env.reset(seed=seed)
        plain.reset(seed=seed)
        lifted, state = env.state()["qvel"][:, up], plain.state()
        assert ((lifted >= 1.0) & (lifted <= 2.0)).all() and lifted.std() > 0.05
        assert torch.equal(state["qvel"][:, up], torch.zeros(16))
        # the events before it drew as the plain task's do: the same reset poses
        assert torch.allclose(env.state()["qpos"], state["qpos"])
    env.step(torch.zeros(16, 12))
    assert (env.state()["qvel"][:, up] < lifted).all()
    env.close()
    plain.close()


def wrong(kind: str):
    """A term declared half or wrong, as a user might."""
    from tests import user_terms
    from warpgym.tasks.terms import Event, Observation, Reward

    return {
        "unknown": {"rewards": {"half": {"weight": 1.0}}},
        "misspelt": {"rewards": {"user_action_rate": Reward(user_terms.scaled_action_rate, -0.1, {"scal": 3.0})}},
        "missing": {"rewards": {"user_action_rate": Reward(user_terms.scaled_action_rate, -0.1)}},
        "not a function": {"policy_obs": {"height": Observation(lambda env, w, i: 0.0, 1)}},
        "drop": {"policy_obs": {"base height": None}},
        "event without its random state": {"events": {"lift": Event(user_terms.base_height, "reset")}},
        "event on no schedule": {"events": {"lift": Event(user_terms.lift_base, "interval", {"speed": (1.0, 2.0)})}},
    }[kind]


@pytest.mark.parametrize("kind, words", [
    ("unknown", "rewards: no term 'half'"),
    ("misspelt", "['user_action_rate']: scaled_action_rate's parameters are ['scale']; unknown ['scal']; missing ['scale']"),
    ("missing", "['user_action_rate']: scaled_action_rate's parameters are ['scale']; missing ['scale']"),
    ("not a function", "is not a @wp.func"),
    ("drop", "no term 'base height' to drop"),
    ("event without its random state", "base_height must take and return the random state"),
    ("event on no schedule", "['lift']: interval=None must be (low, high) seconds between its runs"),
])
def test_a_half_declared_term_is_one_line_that_names_it(kind, words):
    from warpgym.envs.legged import LeggedVecEnv

    with pytest.raises((ValueError, TypeError)) as e:
        LeggedVecEnv("Go1VelocityFlat-v0", num_envs=1, device="cpu", **wrong(kind))
    assert words in str(e.value) and "\n" not in str(e.value)


def test_warpgym_train_trains_a_users_task_from_its_module(tmp_path):
    """`warpgym train --task user_task:UserGo1-v0` imports the user's module, trains two iterations on the CPU and
    evaluates with the user's term in the log; a replay of the run asks for the module rather than import it."""
    run = str(tmp_path / "user")
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([HERE, ROOT, os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-m", "warpgym", "train", "--task", "user_task:UserGo1-v0", "--device",
                           "cpu", "--num-envs", "4", "--max-iterations", "2", "--horizon-len", "8", "--eval-gap", "0",
                           "--eval-envs", "2", "--episode-length", "20", "--no-plots", "--run-dir", run],
                          capture_output=True, text=True, env=env, cwd=str(tmp_path), timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    rows = [json.loads(line) for line in open(os.path.join(run, "metrics.jsonl"))]
    assert [r["iteration"] for r in rows] == [1, 2]
    assert rows[-1]["eval/reward_user_action_rate"] < 0  # the user's term scored the evaluation's episodes
    saved = json.load(open(os.path.join(run, "config.json")))
    assert saved["env_args"]["task"] == "user_task:UserGo1-v0"
    replay = subprocess.run([sys.executable, "-m", "warpgym", "play", run, "--device", "cpu", "--steps", "2"],
                            capture_output=True, text=True, env=env, cwd=str(tmp_path), timeout=600)
    assert replay.returncode == 2 and "pass --import user_task" in replay.stderr, replay.stderr[-2000:]


def test_a_suite_tasks_own_terms_run_in_its_step_beside_gymnasiums():
    """Hopper-v5 with a user's reward (the control cost at twice Gymnasium's weight) and termination: the reward is
    Gymnasium's plus the user's term, reported under its name; the observation and Gymnasium's terms are those of the
    task without them; the termination ends every world once its threshold is above the start's height."""
    import gymnasium as gym

    import warpgym  # noqa: F401  (the ids)
    from tests import user_terms
    from warpgym.tasks.terms import Termination

    def make(below):
        return gym.make_vec("warpgym/Hopper-v5", num_envs=3, device="cpu", rewards=user_terms.SUITE_REWARDS,
                            terminations={"torso_below": Termination(user_terms.torso_below, params={"below": below})})

    plain = gym.make_vec("warpgym/Hopper-v5", num_envs=3, device="cpu")
    envs = make(0.0)  # never below the floor: Gymnasium's terminations alone end episodes
    assert list(envs.task.rewards) == ["user_energy"] and list(plain.task.rewards) == []
    envs.reset(seed=4)
    plain.reset(seed=4)
    torch.manual_seed(0)
    for _ in range(3):
        action = torch.rand(3, 3) * 2 - 1
        obs, reward, terminated, _, info = envs.step(action)
        obs0, reward0, terminated0, _, info0 = plain.step(action)
        assert torch.equal(obs, obs0) and torch.equal(terminated, terminated0)
        assert torch.allclose(info["reward_user_energy"], 2.0 * info0["reward_ctrl"], rtol=1e-5, atol=1e-9)
        assert float(info["reward_user_energy"].abs().min()) > 0
        assert torch.allclose(reward, reward0 + info["reward_user_energy"], atol=1e-6)
    envs.close()
    high = make(1.3)  # above the Hopper's start at 1.25 m: the first step ends every world
    high.reset(seed=4)
    _, _, terminated, truncated, _ = high.step(torch.zeros(3, 3))
    assert terminated.all() and not truncated.any()
    high.close()
    plain.close()


def test_a_robots_own_terms_run_in_its_step_after_isaac_gyms_reward():
    """The Ant with a user's reward (its up projection, read from the step's observation) and termination: the
    reward is Isaac Gym's plus the term, the observation unchanged; a termination that always holds ends every world
    at its first step without the death cost, which only a fall pays."""
    import gymnasium as gym

    import warpgym  # noqa: F401  (the ids)
    from tests import user_terms
    from warpgym.tasks.terms import Termination

    def make(height):
        return gym.make_vec("warpgym/Ant-v0", num_envs=3, device="cpu", rewards=user_terms.ROBOT_REWARDS,
                            terminations={"torso_above": Termination(user_terms.torso_above,
                                                                     params={"height": height})})

    envs, plain = make(5.0), gym.make_vec("warpgym/Ant-v0", num_envs=3, device="cpu")
    envs.reset(seed=2)
    plain.reset(seed=2)
    torch.manual_seed(0)
    for _ in range(3):
        action = torch.rand(3, 8) * 2 - 1
        obs, reward, terminated, _, info = envs.step(action)
        obs0, reward0, terminated0, _, _ = plain.step(action)
        assert torch.equal(obs, obs0) and not terminated.any() and not terminated0.any()
        assert torch.allclose(info["reward_user_upright"], 0.25 * obs[:, 10], atol=1e-7)
        assert torch.allclose(reward, reward0 + info["reward_user_upright"], atol=1e-5)
    envs.close()
    low = make(0.0)  # the torso is always above the floor
    low.reset(seed=2)
    _, reward, terminated, _, _ = low.step(torch.zeros(3, 8))
    assert terminated.all() and (reward != low.task.death_cost).all()
    low.close()
    plain.close()


def train_user_task(task: str, tmp_path) -> tuple[str, list[dict], dict]:
    """`warpgym train --task user_task:TASK`, two iterations on the CPU: the run, its rows, its environment."""
    run = str(tmp_path / task)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([HERE, ROOT, os.environ.get("PYTHONPATH", "")])}
    done = subprocess.run([sys.executable, "-m", "warpgym", "train", "--task", f"user_task:{task}", "--device", "cpu",
                           "--num-envs", "4", "--max-iterations", "2", "--horizon-len", "8", "--eval-gap", "0",
                           "--eval-envs", "2", "--episode-length", "20", "--no-plots", "--run-dir", run],
                          capture_output=True, text=True, env=env, cwd=str(tmp_path), timeout=900)
    assert done.returncode == 0, done.stderr[-3000:]
    rows = [json.loads(line) for line in open(os.path.join(run, "metrics.jsonl"))]
    assert [r["iteration"] for r in rows] == [1, 2]
    assert json.load(open(os.path.join(run, "config.json")))["env_args"]["task"] == f"user_task:{task}"
    return run, rows, env


def test_warpgym_train_trains_a_users_robot_task_from_its_module(tmp_path):
    """`warpgym train --task user_task:UserAnt` trains with the user's term in its log and the Ant's preset."""
    run, rows, _ = train_user_task("UserAnt", tmp_path)
    assert rows[-1]["eval/reward_user_upright"] > 0
    config = json.load(open(os.path.join(run, "config.json")))
    assert config["reward_scale"] == 0.01  # the Ant's preset (the suite's is 0.1)


def test_warpgym_train_and_eval_take_a_users_suite_task_from_its_module(tmp_path):
    """`warpgym train --task user_task:UserHopper-v5` trains two iterations with the user's term in its log;
    `warpgym eval` scores the policy in Gymnasium's own Hopper-v5, both envs without the task's own terms."""
    run, rows, env = train_user_task("UserHopper-v5", tmp_path)
    assert rows[-1]["eval/reward_user_energy"] < 0
    out = str(tmp_path / "eval.json")
    scored = subprocess.run([sys.executable, "-m", "warpgym", "eval", run, "--import", "user_task", "--episodes", "2",
                             "--seeds", "0", "--json", out], capture_output=True, text=True, env=env,
                            cwd=str(tmp_path), timeout=900)
    assert scored.returncode == 0, scored.stderr[-3000:]
    assert "the task's own terms ['user_energy', 'torso_below'] shaped its training only" in scored.stdout
    result = json.load(open(out))
    assert "reward_user_energy" not in result["warpgym_terms"] and "reward_ctrl" in result["warpgym_terms"]
    # the same starts, the same task in both envs: the returns agree as the suite's judge tests require
    assert result["gymnasium_over_warpgym"] == pytest.approx(1.0, abs=0.05)


def test_an_observation_with_history_holds_its_last_frames_oldest_first():
    """A term with ``history=3``: its three frames after a reset are the first observation, then each step shifts
    them (oldest first), against the same term without history in the same observation; a world reset in a step
    starts its frames over."""
    from kernels.legged import observations as terms
    from warpgym.envs.legged import LeggedVecEnv
    from warpgym.tasks.legged.model import policy_terms
    from warpgym.tasks.terms import Observation

    env = LeggedVecEnv("Go1VelocityFlat-v0", num_envs=3, device="cpu", seed=1, events={"push_robot": None},
                       observation_noise=False,
                       policy_obs={"past_joint_vel": Observation(terms.joint_vel, lambda d: d.joints, history=3)})
    now = slice(21, 33)  # joint_vel: after the base's 9 entries and the 12 joint positions

    def frames(obs):
        return obs[:, 48:60].clone(), obs[:, 60:72].clone(), obs[:, 72:84].clone()

    obs, _ = env.reset(seed=0)
    assert obs.shape == (3, 48 + 36)
    assert dict((n, s) for n, s, _ in policy_terms(env.task, env.index, 12))["past_joint_vel"] == 36
    seen = [obs[:, now].clone()]
    assert all(torch.equal(f, seen[0]) for f in frames(obs))
    torch.manual_seed(0)
    for step in range(4):
        obs, _, terminated, truncated, _ = env.step(torch.rand(3, 12) * 2 - 1)
        seen.append(obs[:, now].clone())
        oldest, middle, newest = frames(obs)
        assert torch.equal(newest, seen[-1])
        went_on = ~(terminated | truncated)
        assert torch.equal(middle[went_on], seen[-2][went_on]) and torch.equal(oldest[went_on], seen[max(len(seen) - 3, 0)][went_on])
        assert float((seen[-1] - seen[-2]).abs().max()) > 0  # the joints move: the frames differ
    env.close()
    with pytest.raises(ValueError, match=r"history=0 must be a number of observations, 1 or more"):
        LeggedVecEnv("Go1VelocityFlat-v0", num_envs=1, device="cpu",
                     policy_obs={"bad": Observation(terms.joint_vel, 12, history=0)})


def test_an_event_from_a_module_with_postponed_annotations_is_taken(tmp_path, monkeypatch):
    """A user's module under ``from __future__ import annotations`` (its annotations strings): its event's
    function is checked by the types Warp resolves, not refused for a string return annotation."""
    import importlib

    from warpgym.tasks.terms import Event, signature

    (tmp_path / "late_events.py").write_text(
        "from __future__ import annotations\n"
        "import warp as wp\n"
        "from kernels.legged.params import LeggedEnv\n\n"
        "@wp.func\n"
        "def nudge(env: LeggedEnv, w: int, rng: wp.uint32) -> wp.uint32:\n"
        "    env.d.qvel[w, env.r.root_dof] = wp.randf(rng, 0.0, 0.1)\n"
        "    return rng\n\n"
        "@wp.func\n"
        "def no_state(env: LeggedEnv, w: int, rng: wp.uint32) -> float:\n"
        "    return 0.0\n\n"
        "def made(speed):\n"  # a term made by a function: its return type a name of the closure, as Warp reads it
        "    State = wp.uint32\n"
        "    @wp.func\n"
        "    def kick(env: LeggedEnv, w: int, rng: State) -> State:\n"
        "        env.d.qvel[w, env.r.root_dof] = speed\n"
        "        return State(rng)\n"
        "    return kick\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    late = importlib.import_module("late_events")
    assert signature(Event(late.nudge, "reset"), "event", "events['nudge']") is None
    with pytest.raises(TypeError, match="no_state must take and return the random state"):
        signature(Event(late.no_state, "reset"), "event", "events['no_state']")
    assert signature(Event(late.made(0.1), "reset"), "event", "events['kick']") is None
