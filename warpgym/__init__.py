"""warpgym: thousands of Ant and Humanoid robots simulated at once with Newton and NVIDIA Warp."""

import warp as _wp

_wp.config.quiet = True

from warpgym.device import default_device, resolve_device  # noqa: E402
from warpgym.registration import register_envs  # noqa: E402
from warpgym.sim import Sim  # noqa: E402

register_envs()

__all__ = ["Sim", "default_device", "resolve_device"]
__version__ = "0.1.0"
