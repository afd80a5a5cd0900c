"""Compile the simulation's Warp modules in parallel, before their first launch.

With an empty kernel cache (a fresh machine), Warp compiles each module the first time one of
its kernels is launched, one module after another: about 100 s for the Ant on an H100, all of it
before the first step. Two things shorten that:

- The modules every step needs and that exist before the model does (Newton's MuJoCo glue,
  MuJoCo Warp's static modules, warpgym's kernels) are compiled on a thread pool while the model
  is built on the main thread. NVRTC and LLVM run outside the GIL, so the compiles overlap.
- No adjoint (backward) code for Newton's MuJoCo glue module, as for warpgym's own kernels:
  nothing differentiates through them, and the adjoints are over half of that module's compile.

MuJoCo Warp's specialised kernels, which its closures create during the solver's construction
and first step, still compile one by one when they are first launched. Five of them factor
small matrices with Warp's tile Cholesky, which by default links NVIDIA's libmathdx and is the
slowest part of a cold start; ``use_mathdx(False)`` compiles Warp's own implementation instead.
"""

from __future__ import annotations

import importlib
import os
import threading
from concurrent.futures import ThreadPoolExecutor

import warp as wp

# Importable before the model exists, and launched by every Sim step or reset.
SIM_MODULES = (
    "newton._src.solvers.mujoco.kernels",
    "mujoco_warp._src.forward",
    "mujoco_warp._src.smooth",
    "mujoco_warp._src.set_const",
    "mujoco_warp._src.derivative",
    "mujoco_warp._src.passive",
    "mujoco_warp._src.solver",
    "mujoco_warp._src.support",
    "mujoco_warp._src.constraint",
    "kernels.actions",
    "kernels.locomotion",
    "kernels.resets",
    "kernels.tensor_api",
    "kernels.solver_load",
)
# Dependencies' modules compiled without adjoints (warpgym's own set this in their source).
NO_BACKWARD = ("newton._src.solvers.mujoco.kernels",)


def _import(name: str):
    try:
        return importlib.import_module(name)
    except ImportError:  # a private path that moved in another Newton or MuJoCo Warp version
        return None


class Preload:
    """Start compiling ``SIM_MODULES`` for ``device`` in the background; ``wait()`` before using them."""

    def __init__(self, device: str, workers: int | None = None):
        self.device = device
        self.error: BaseException | None = None
        for name in NO_BACKWARD:
            module = _import(name)
            if module is not None and wp.get_module_options(module).get("enable_backward", True):
                wp.set_module_options({"enable_backward": False}, module=module)
        self.modules = [m for m in map(_import, SIM_MODULES) if m is not None]
        self.workers = workers or max(1, min(len(self.modules), os.cpu_count() or 1))
        self._thread = threading.Thread(target=self._run, name="warpgym-preload", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        try:
            with ThreadPoolExecutor(self.workers) as pool:
                for f in [pool.submit(wp.load_module, m, device=self.device, max_workers=0) for m in self.modules]:
                    f.result()
        except BaseException as e:  # the same failure resurfaces, with its context, at the first launch
            self.error = e

    def wait(self) -> None:
        self._thread.join()


def use_mathdx(enabled: bool) -> None:
    """Whether Warp's tile Cholesky (and other tile solvers) link libmathdx, for kernels compiled
    from now on in this process. A process-wide Warp setting; call it before building any env."""
    wp.config.enable_mathdx_solver = bool(enabled)
