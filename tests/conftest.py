"""Shared fixtures. Every test runs on Warp's CPU backend with a handful of envs; models are built
once per session where a test can start from a reset instead of a fresh build."""

import os
import sys

import pytest

os.environ.setdefault("WARP_CACHE_PATH", os.path.expanduser("~/.cache/warp"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

DEVICE = "cpu"


@pytest.fixture(scope="session")
def ant_env():
    from warpgym.envs import LocomotionVecEnv

    return LocomotionVecEnv("Ant", num_envs=4, device=DEVICE, seed=0)


@pytest.fixture(scope="session")
def humanoid_env():
    from warpgym.envs import LocomotionVecEnv

    return LocomotionVecEnv("Humanoid", num_envs=3, device=DEVICE, seed=0)


@pytest.fixture(scope="session")
def ant_sim():
    """A bare Sim (no task on it) for Tensor API tests; tests put it in the state they need."""
    from warpgym import Sim

    return Sim("ant", num_envs=3, device=DEVICE, seed=0)
