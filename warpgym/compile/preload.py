"""Compile the simulation's Warp modules in parallel, before their first launch.

With an empty kernel cache (a fresh machine), Warp compiles each module the first time one of
its kernels is launched, one module after another: about 100 s for the Ant on an H100, all of it
before the first step. Two things shorten that:

- The modules every step needs and that exist before the model does (Newton's MuJoCo glue,
  MuJoCo Warp's static modules, warpgym's kernels) are compiled on a thread pool while the model
  is built on the main thread. NVRTC and LLVM run outside the GIL, so the compiles overlap.
- No adjoint (backward) code for Newton's MuJoCo glue module, as for warpgym's own kernels:
  nothing differentiates through them, and the adjoints are over half of that module's compile.
- MuJoCo Warp's specialised kernels exist only once its closures run, during the solver's
  construction and first step, and Warp would compile them one by one as they are first launched.
  ``record_modules(fn)`` runs ``fn`` once with every launch turned into a note of the module it
  needs. ``Sim`` rehearses a two-world model's finalize, solver construction and substep this way
  and queues the modules on the pool above (``Preload.add``) while it builds the full model; the env checks its whole step with ``compile_ahead``, which
  compiles whatever is still missing, side by side. Five of those kernels factor small matrices with Warp's tile
  Cholesky, which by default links NVIDIA's libmathdx (slow to compile, fast to run). Those LTO
  objects are built in child processes first (``warpgym.compile.mathdx``), since Warp builds them one at
  a time under its code-generation lock; ``use_mathdx(False)`` compiles Warp's own implementation
  instead.

``warpgym.compile.log`` records what this process compiled and where the time went, for the
start-up timeline that ``warpgym train`` prints.
"""

from __future__ import annotations

import importlib
import os
import threading
import time
from concurrent.futures import ThreadPoolExecutor

import warp as wp
import warp._src.context as _wp_context

from warpgym.compile import log as compile_log, mathdx

# Importable before the model exists, and launched by every Sim step or reset.
SIM_MODULES = (
    "newton._src.solvers.mujoco.kernels",
    "newton._src.sim.articulation",
    "mujoco_warp._src.forward",
    "mujoco_warp._src.smooth",
    "mujoco_warp._src.set_const",
    "mujoco_warp._src.derivative",
    "mujoco_warp._src.passive",
    "mujoco_warp._src.solver",
    "mujoco_warp._src.support",
    "mujoco_warp._src.constraint",
    "kernels.common",
    "kernels.robots.actions",
    "kernels.robots.step",
    "kernels.robots.resets",
    "kernels.tensor_api",
    "kernels.solver_load",
)
# Dependencies' modules compiled without adjoints (warpgym's own set this in their source).
NO_BACKWARD = ("newton._src.solvers.mujoco.kernels", "newton._src.sim.articulation")


def _import(name: str):
    try:
        return importlib.import_module(name)
    except ImportError:  # a private path that moved in another Newton or MuJoCo Warp version
        return None


class Preload:
    """Compile ``SIM_MODULES`` for ``device`` on a thread pool, starting now; ``add(fn)`` queues the
    modules that ``fn`` would launch (``record_modules``) on the same pool. ``wait()`` before
    launching anything that needs them. A failed compile is kept in ``error``, not raised: the
    launch that needs the module compiles it again and reports the failure where it happens."""

    def __init__(self, device: str, workers: int | None = None):
        self.device = device
        self.error: BaseException | None = None
        self.stopped_early: BaseException | None = None
        for name in NO_BACKWARD:
            module = _import(name)
            if module is not None and wp.get_module_options(module).get("enable_backward", True):
                wp.set_module_options({"enable_backward": False}, module=module)
        self.modules = [m for m in map(_import, SIM_MODULES) if m is not None]
        self.workers = workers or max(1, os.cpu_count() or 1)
        self._pool = ThreadPoolExecutor(self.workers, thread_name_prefix="warpgym-compile")
        self._futures = [self._pool.submit(wp.load_module, m, device=device, max_workers=0) for m in self.modules]

    def add(self, fn) -> int:
        """Queue the modules ``fn``'s launches need; ``fn`` runs now, launch-free, in this thread."""
        found, self.stopped_early = record_modules(fn)
        todo = _not_loaded(found)
        self._futures += submit_loads(self._pool, todo)
        return len(todo)

    def wait(self) -> None:
        for f in self._futures:
            try:
                f.result()
            except BaseException as e:  # noqa: PERF203
                self.error = self.error or e
        self._pool.shutdown()


def use_mathdx(enabled: bool) -> None:
    """Whether Warp's tile Cholesky (and other tile solvers) link libmathdx, for kernels compiled
    from now on in this process. A process-wide Warp setting; call it before building any env."""
    wp.config.enable_mathdx_solver = bool(enabled)


# ----------------------------------------------------------------------------- compile ahead
# Warp compiles a module inside ``Module.load``, which every launch calls first. One wrapper,
# installed once, both logs real compiles (``warpgym.compile.log``, for the start-up timeline) and,
# in a thread that is recording, answers "not loaded" so that the launch returns without running
# (Warp's ``launch`` skips a kernel whose module did not load).
_local = threading.local()
_original_load = None


def _variant(module, block_dim):
    return block_dim if block_dim is not None else module.options["block_dim"]  # as Module.load picks it


def _is_loaded(module, device, block_dim) -> bool:
    return module.execs.get((getattr(device, "context", None), _variant(module, block_dim))) is not None


def _not_loaded(found: list) -> list:
    return [(m, d, b) for m, d, b in found if not _is_loaded(m, d, b)]


def _cache_dir_of(module, block_dim) -> str | None:
    try:
        return os.path.join(wp.config.kernel_cache_dir, module.get_module_identifier(block_dim))
    except Exception:  # a Warp without this helper: compiles are then not told from cache hits
        return None


def is_cached(module, block_dim=None) -> bool:
    """Whether the kernel cache holds this module variant (a folder for its content hash)."""
    cached = _cache_dir_of(module, _variant(module, block_dim))
    return cached is None or os.path.isdir(cached)


_variant_locks: dict = {}
_variant_locks_guard = threading.Lock()


def _lock_of(module, device, block_dim) -> threading.Lock:
    # Warp has no lock of its own here: two threads loading one variant would both compile it (a
    # launch on the main thread while the pool is compiling that module, say). The second waits.
    key = (id(module), getattr(device, "context", None), _variant(module, block_dim))
    with _variant_locks_guard:
        return _variant_locks.setdefault(key, threading.Lock())


def _load(module, device, block_dim=None, *args, **kwargs):
    notes = getattr(_local, "notes", None)
    if notes is not None:
        notes.setdefault((module.name, block_dim, str(device)), (module, device, block_dim))
        return None
    if _is_loaded(module, device, block_dim):
        return _original_load(module, device, block_dim, *args, **kwargs)
    with _lock_of(module, device, block_dim):
        if _is_loaded(module, device, block_dim):  # loaded by the thread this one waited for
            return _original_load(module, device, block_dim, *args, **kwargs)
        record = compile_log.begin(module, _variant(module, block_dim))
        was_cached = is_cached(module, block_dim)
        try:
            return _original_load(module, device, block_dim, *args, **kwargs)
        finally:
            compile_log.end(record, compiled=not was_cached)


def _install() -> None:
    global _original_load
    if _original_load is None:
        _original_load = _wp_context.Module.load
        _wp_context.Module.load = _load


_install()


def _recording_capture_while(condition, while_body, stream=None, **kwargs):
    while_body(**kwargs)  # once: the body's launches are noted, the condition is never read


def _recording_capture_if(condition, on_true=None, on_false=None, stream=None, **kwargs):
    for branch in (on_true, on_false):  # both branches: either may run later
        if callable(branch):
            branch(**kwargs)


def _recording_block_size(kernel, device=None, *args, **kwargs):
    device = wp.get_device(device)
    if device.is_cpu:
        return 1, 1  # as Warp answers for the CPU, without loading anything
    # Warp loads the module's default variant to query occupancy: that variant is needed too.
    _local.notes.setdefault((kernel.module.name, None, str(device)), (kernel.module, device, None))
    return 256, 1


def _recording_empty(*args, **kwargs):
    return wp.zeros(*args, **kwargs)  # no kernel fills it: host code reading it back sees zeros, not noise


_RECORDING_PATCHES = {"capture_while": _recording_capture_while, "capture_if": _recording_capture_if,
                      "get_suggested_block_size": _recording_block_size, "empty": _recording_empty}
_patch_lock = threading.Lock()


def record_modules(fn) -> tuple[list, BaseException | None]:
    """Run ``fn`` with every Warp launch in this thread skipped and noted. Returns the
    (module, device, block_dim) triples it would have loaded, and the error that stopped ``fn``
    early, if any (a host read of a buffer no kernel filled can send it down another path).

    Device loops (``wp.capture_while``) run their body once and ``wp.capture_if`` both branches,
    so every kernel the step can reach is noted. Other threads launch as usual meanwhile."""
    _install()
    notes: dict = {}
    error = None
    with _patch_lock:
        saved = {name: getattr(wp, name) for name in _RECORDING_PATCHES}
        for name, patched in _RECORDING_PATCHES.items():
            setattr(wp, name, _thread_local_patch(patched, saved[name]))
        _local.notes = notes
        try:
            fn()
        except Exception as e:  # what was noted before still compiles ahead; the rest at its launch
            error = e
        finally:
            _local.notes = None
            for name, original in saved.items():
                setattr(wp, name, original)
    return list(notes.values()), error


def _thread_local_patch(patched, original):
    def dispatch(*args, **kwargs):
        return (patched if getattr(_local, "notes", None) is not None else original)(*args, **kwargs)
    return dispatch


def submit_loads(pool, todo: list) -> list:
    """Load each (module, device, block_dim) of ``todo`` on ``pool``. On a GPU, the libmathdx LTO
    objects that modules about to compile would build are first started in child processes
    (``warpgym.compile.mathdx``), and those modules load once theirs are built; the others load at once."""
    waits = _start_lto_builds(todo)
    plain = [pool.submit(m.load, d, b) for m, d, b in todo if (id(m), _variant(m, b)) not in waits]
    return plain + [pool.submit(_load_after, waits[(id(m), _variant(m, b))], m, d, b)
                    for m, d, b in todo if (id(m), _variant(m, b)) in waits]


def _load_after(builds, module, device, block_dim):
    for b in builds:
        b.wait()  # a failed child only means Warp builds that object itself, as it would have anyway
    return module.load(device, block_dim)


def lto_in_processes() -> bool:
    """Whether libmathdx objects are built in child processes (``WARPGYM_LTO_PROCESSES=0``: no)."""
    return os.environ.get("WARPGYM_LTO_PROCESSES", "1") != "0"


def _start_lto_builds(todo: list) -> dict:
    waits = {}
    if not lto_in_processes():
        return waits
    for m, d, b in todo:
        if not getattr(d, "is_cuda", False) or is_cached(m, b):
            continue
        try:
            requests = mathdx.lto_requests(m, m._get_compile_arch(d), _variant(m, b))
        except Exception:  # noqa: BLE001,S112  (a Warp without these internals: the module builds its own)
            continue
        if requests:
            waits[(id(m), _variant(m, b))] = mathdx.start_builds(requests)
    return waits


def compile_ahead(fn, workers: int | None = None) -> dict:
    """Find the Warp modules ``fn`` launches (``record_modules``), without running it, and load
    them all at once on a thread pool: compiled side by side on an empty kernel cache, read from
    it otherwise. ``fn``'s launches have no effect; its host-side effects do, so ``fn`` should be
    one that can run twice (a constructor whose result is dropped, or a step about to be captured).
    Returns what was done, for the start-up timeline."""
    start = time.perf_counter()
    before = len(compile_log.compiled_modules())
    found, error = record_modules(fn)
    todo = _not_loaded(found)
    if todo:
        with ThreadPoolExecutor(workers or max(1, min(len(todo), os.cpu_count() or 1))) as pool:
            for f in submit_loads(pool, todo):
                try:
                    f.result()
                except Exception:  # the launch that needs it compiles it again and reports the error there
                    pass
    return {"modules": len(found), "loaded": len(todo), "compiled": len(compile_log.compiled_modules()) - before,
            "seconds": time.perf_counter() - start, "stopped_early": repr(error) if error else None}


def kernel_cache() -> tuple[str, int]:
    """Warp's kernel cache folder (``WARP_CACHE_PATH`` moves it) and how many compiled modules it holds."""
    wp.init()
    path = wp.config.kernel_cache_dir
    try:
        count = sum(1 for name in os.listdir(path) if name.startswith("wp_"))
    except OSError:
        count = 0
    return path, count


def bytecode_note() -> str:
    """A hint when Python recompiles its packages' source at every start: no cached bytecode for
    torch and none will be written (PYTHONDONTWRITEBYTECODE, common in container images). On an
    H100 host that added about 18 s to a cold start; ``python -m compileall`` writes the cache once,
    as ``pip install`` does by default."""
    import importlib.util  # noqa: PLC0415
    import sys  # noqa: PLC0415

    torch_spec = importlib.util.find_spec("torch")
    origin = torch_spec.origin if torch_spec else None
    if not sys.flags.dont_write_bytecode or origin is None:
        return ""
    if os.path.exists(importlib.util.cache_from_source(origin)):
        return ""
    site = os.path.dirname(os.path.dirname(origin))
    return (f"Python writes no bytecode here (PYTHONDONTWRITEBYTECODE) and {site} has none, so every start "
            f"recompiles the packages' source; run `python -m compileall -q {site}` once to cache it")
