"""warpgym: thousands of robots simulated at once on one GPU by NVIDIA Warp kernels and MuJoCo Warp (through Newton
for its own Ant and Humanoid), as Gymnasium vector envs whose step is one CUDA graph: Gymnasium's MuJoCo suite,
Isaac Gym's Ant and Humanoid, mjlab's legged velocity tasks (``warpgym.tasks.registry``)."""

import os as _os

import warp as _wp

# Warp announces every module it loads at INFO; keep warnings and errors, unless WARPGYM_WARP_INFO=1
# asks for the per-module load and compile times.
if not _os.environ.get("WARPGYM_WARP_INFO"):
    if getattr(_wp.config, "log_level", None) is not None and _wp.config.log_level < _wp.LOG_WARNING:
        _wp.config.log_level = _wp.LOG_WARNING
    _wp.config.quiet = True

from warpgym.sim.device import default_device, resolve_device  # noqa: E402
from warpgym.envs.registration import register_envs  # noqa: E402
from warpgym.sim.simulator import Sim  # noqa: E402

register_envs()

__all__ = ["Sim", "default_device", "resolve_device"]
__version__ = "0.1.0"
