"""The simulation core: ``Sim`` (warpgym's Ant and Humanoid, replicated and stepped by Newton's MuJoCo Warp solver)
and ``mjw_sim.MjwSim`` (a MuJoCo compile stepped by MuJoCo Warp itself: the suite's and the legged tasks'), their
physics settings, the robot models, the Isaac Gym-like Tensor API, ray casts, stream ordering and input checks."""

from warpgym.sim.simulator import Sim

__all__ = ["Sim"]
