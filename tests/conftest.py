"""Shared fixtures. Every test runs on Warp's CPU backend with a handful of envs; models are built
once per session where a test can start from a reset instead of a fresh build."""

import os
import sys

import pytest

os.environ.setdefault("WARP_CACHE_PATH", os.path.expanduser("~/.cache/warp"))
# Under pytest-xdist (the README's command: a worker a core) each worker, and every process its tests start, gets
# one OpenMP thread, as torchrun gives its workers: with torch's default of a thread a core, two workers' threads
# spin for each other's cores (the overlapped point-mass test took under 4 s alone, 59-70 s beside another worker).
if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ.setdefault("OMP_NUM_THREADS", "1")
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
