"""The simulation core: ``Sim`` (replicated robots stepped by Newton's MuJoCo Warp solver), its
physics settings, the robot models, the Isaac Gym-like Tensor API, stream ordering and input checks."""

from warpgym.sim.simulator import Sim

__all__ = ["Sim"]
