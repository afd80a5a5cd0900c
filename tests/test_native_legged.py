"""The legged tasks' sim-to-sim check (warpgym.native_legged, ``warpgym eval`` of a legged run): the same policy
over the same schedule of commands in native MuJoCo (float64, ``mj_step``) and in warpgym's env tracks alike."""

import numpy as np
import pytest
import torch

from warpgym.native_legged import SCHEDULE, commands, native_episodes, warpgym_episodes
from warpgym.tasks.legged import LEGGED

pytestmark = pytest.mark.slow


@pytest.mark.parametrize("pose", ["default", "splayed"])
def test_one_policy_tracks_alike_in_native_mujoco_and_warpgym(pose):
    """Holding the default pose, and a splayed one (hips out, a crouch) that moves the base off its command: the
    tracking errors of the two simulators within 1 % of each other, and no falls in either."""
    task = LEGGED["Go1VelocityFlat-v0"].replace(episode_length_s=4.0)
    action = np.zeros(12, np.float32)
    if pose == "splayed":
        action[[0, 3]], action[[6, 9]] = 3.0, -3.0
    native = native_episodes(task, lambda obs: action, 2)
    ours = warpgym_episodes(task, lambda obs: torch.as_tensor(action).expand(obs.shape[0], 12), 2)
    assert native.falls == ours.falls == 0
    assert abs(native.error_xy / ours.error_xy - 1) < 0.01 and abs(native.error_yaw / ours.error_yaw - 1) < 0.01
    assert native.error_xy > 0.3  # the schedule's commands are not met standing still


def test_the_schedule_cycles_its_commands():
    table = commands(1000, 0.02)
    assert table.shape == (1000, 3) and np.allclose(table[0], SCHEDULE[0]) and np.allclose(table[150], SCHEDULE[1])
    assert len({tuple(c) for c in table}) == len(SCHEDULE)
