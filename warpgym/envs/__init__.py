"""Environments built on ``warpgym.Sim``."""

from warpgym.envs.locomotion import LocomotionVecEnv

__all__ = ["LocomotionVecEnv"]
