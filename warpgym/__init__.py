"""warpgym: thousands of Ant and Humanoid robots simulated at once with Newton and NVIDIA Warp."""

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
