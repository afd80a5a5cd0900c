"""One forward speed everywhere: a robot carried forward at a known speed reads that speed from every
reporter (the env's episode statistics, evaluations, training rows, clips, and sim2sim.py in warpgym and
in native MuJoCo), for a full episode, an episode cut short and a clip that spans a reset.

The conveyor writes each robot's root state before every step through the Tensor API: high above the
ground, moving forward at SPEED and sideways at DRIFT (sideways is not forward), motors off
(power_scale 0), so nothing but the conveyor moves the root."""

import numpy as np
import pytest
import torch

from warpgym.cli import sim2sim

SPEED, DRIFT, HEIGHT = 2.5, 0.8, 1.2  # m/s forward, m/s sideways, m above the ground
EPISODE = 40  # steps: short enough for a clip and a training iteration to span a reset


def carried_pose(steps: np.ndarray | torch.Tensor, dt: float):
    """Root position after ``steps`` control steps on the conveyor."""
    return SPEED * dt * steps, DRIFT * dt * steps


class Conveyor:
    """A ``LocomotionVecEnv`` whose robots the conveyor carries; everything else is the env's."""

    graph_capturable = False  # the root state is written from the host before each step

    def __init__(self, env):
        self.env = env
        self.ids = torch.arange(env.num_envs)

    def __getattr__(self, name):
        return getattr(self.env, name)

    def reset(self, *, seed=None, options=None):
        return self.env.reset(seed=seed)

    def step(self, actions):
        x, y = carried_pose(self.env.episode_steps.float(), self.env.task.dt)
        state = torch.zeros(self.env.num_envs, 13)
        state[:, 0], state[:, 1], state[:, 2], state[:, 6] = x, y, HEIGHT, 1.0
        state[:, 7], state[:, 8] = SPEED, DRIFT
        self.env.sim.set_actor_root_state_tensor_indexed(state, self.ids)
        return self.env.step(actions)


class NativeConveyor:
    """The same conveyor under a ``NativeRobot`` (sim2sim.py's second simulator)."""

    def __init__(self, robot):
        self.robot, self.steps = robot, 0

    def __getattr__(self, name):
        return getattr(self.robot, name)

    def reset(self, rng):
        self.robot.reset(rng)
        self.steps = 0

    def step(self, actions, active=None):
        s = self.robot.state()
        x, y = carried_pose(np.full(self.robot.copies, self.steps), self.robot.task.dt)
        s["root_pose"][:, 0], s["root_pose"][:, 1], s["root_pose"][:, 2] = x, y, HEIGHT
        s["root_pose"][:, 3:] = (0.0, 0.0, 0.0, 1.0)
        s["root_vel"][:] = (SPEED, DRIFT, 0.0, 0.0, 0.0, 0.0)
        self.robot.set_state(s["root_pose"], s["root_vel"], s["dof_pos"], s["dof_vel"])
        self.steps += 1
        return self.robot.step(actions, active)


def still(obs):
    return torch.zeros(obs.shape[0], 8)


class Still:
    """A policy for agents.evaluate that always sends zero actions."""

    act_deterministic = staticmethod(still)


@pytest.fixture(scope="module")
def conveyor():
    from warpgym.envs import LocomotionVecEnv

    return Conveyor(LocomotionVecEnv("Ant", num_envs=2, device="cpu", seed=0, max_episode_steps=EPISODE,
                                     power_scale=0.0))


def close(value) -> bool:
    return abs(float(value) - SPEED) <= 0.01 * SPEED


def test_the_env_reports_the_conveyor_speed_for_ended_and_running_episodes(conveyor):
    conveyor.reset(seed=0)
    for step in range(1, EPISODE + 1):
        _, _, terminated, truncated, info = conveyor.step(torch.zeros(2, 8))
        if step == 25:  # cut short: the episode so far
            assert all(close(s) for s in info["episode_so_far"]["s"]), info["episode_so_far"]["s"]
    assert truncated.all() and not terminated.any()
    assert info["episode"]["_s"].all() and all(close(s) for s in info["episode"]["s"]), info["episode"]["s"]
    assert (info["episode_so_far"]["s"] == 0).all()  # the next episode has just begun


@pytest.mark.parametrize("steps", [EPISODE, 25], ids=["full episode", "cut short"])
def test_evaluation_reports_the_conveyor_speed(conveyor, steps):
    from agents.evaluate import evaluate

    result = evaluate(conveyor, Still(), lambda o: o, steps)
    assert close(result["eval/speed"]), result
    assert result["eval/length"] == steps


def test_a_clip_spanning_a_reset_reports_the_conveyor_speed(conveyor):
    from agents.evaluate import evaluate
    from warpgym.media.clips import StateRecorder
    from warpgym.media.robots import clip_forward_speed

    steps = EPISODE + 30
    recorder = StateRecorder(steps + 1, copies=2)
    evaluate(conveyor, Still(), lambda o: o, steps, recorder)
    states = recorder.states()
    assert (states["episode_steps"][EPISODE] == 0).all()  # the reset is inside the clip
    x = states["root_pose"][:, :, 0]
    assert x[EPISODE - 1].min() > 1.5 and x[EPISODE].max() < 0.1  # ... and jumps back by 1.6 m
    speeds = clip_forward_speed(conveyor.task, states)
    assert all(close(s) for s in speeds), speeds
    naive = (x[-1] - x[0]) / (steps * conveyor.task.dt)  # what counting the reset as travel would give
    assert all(not close(s) for s in naive)


def test_training_rows_report_the_conveyor_speed(conveyor):
    from agents import Config, OnPolicyRunner
    from warpgym.tasks.presets import PRESETS

    cfg = Config.from_preset(PRESETS["Ant"], horizon_len=16, minibatch_size=16, seed=0)
    runner = OnPolicyRunner(conveyor, cfg, print_fn=lambda s: None)
    rows = runner.learn(max_iterations=4)
    ended = [r for r in rows if r["episodes"]]
    assert ended and all(close(r["speed"]) for r in ended), [(r["episodes"], r["speed"]) for r in rows]


@pytest.mark.parametrize("steps", [EPISODE + 10, 25], ids=["past an episode's end", "cut short"])
def test_sim2sim_reports_the_conveyor_speed_in_both_simulators(conveyor, steps):
    from warpgym.native.robots import NativeRobot
    from warpgym.tasks.robots import get_task

    assert close(sim2sim.play_warpgym(conveyor, still, steps, seed=0)["forward_speed"])
    robot = NativeConveyor(NativeRobot(get_task("Ant").replace(power_scale=0.0), copies=2))
    assert close(sim2sim.play_native(robot, still, steps, seed=0)["forward_speed"])
