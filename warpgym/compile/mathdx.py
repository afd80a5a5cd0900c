"""Build libmathdx's LTO objects side by side, in child processes, before the modules that link them.

MuJoCo Warp factors small matrices with Warp's tile Cholesky, which by default links NVIDIA's
libmathdx (cuSolverDx; ``tile_matmul`` likewise links cuBLASDx). Warp builds each such LTO object
while it generates the module's code, and two things serialise that on an empty cache:

- code generation runs under one process-wide lock, so an LTO build (about a second each) holds
  up every other module's code generation;
- libmathdx builds one object at a time per process, whatever the thread (measured: four builds on
  four threads take as long as one after another).

``lto_requests`` generates a module's code once with every LTO build that would miss Warp's
persistent LTO cache (``<kernel cache>/lto``) replaced by a note of its arguments; ``start_builds``
runs noted builds in child processes that imports Warp alone and sees no GPU. When the module
then compiles, its code generation finds every object in the cache. The notes hold the arguments
Warp itself passes, so the objects are the ones it would have built.

This wraps private functions of the pinned warp-lang 1.19 (``build.build_lto_*``,
``build._build_lto_base``, ``Module._run_codegen``); in a Warp without them ``lto_requests`` finds
nothing and the modules compile as before.
"""

from __future__ import annotations

import inspect
import os
import pickle
import subprocess
import sys
import threading
import time
from dataclasses import dataclass

import warp as wp
import warp._src.build as _wp_build

from warpgym.compile import log as compile_log

# Warp builtins whose CUDA code links a libmathdx LTO object (their lto_dispatch_func in warp._src.builtins)
LTO_BUILTINS = ("tile_cholesky", "tile_lower_solve", "tile_upper_solve", "tile_matmul", "tile_fft", "tile_ifft")
_BUILDERS = ("build_lto_solver", "build_lto_dot", "build_lto_fft")
_local = threading.local()
_originals: dict = {}


@dataclass
class Request:
    """One LTO object to build: its symbol (Warp's cache key) and the builder call that makes it."""

    symbol: str
    builder: str
    arguments: dict


def _noting_builder(name: str, original):
    signature = inspect.signature(original)

    def build_or_note(*args, **kwargs):
        if getattr(_local, "notes", None) is not None:
            bound = signature.bind(*args, **kwargs)
            _local.call = (name, {k: v for k, v in bound.arguments.items() if k != "builder"})
        return original(*args, **kwargs)

    build_or_note.__wrapped_by_warpgym__ = True
    return build_or_note


def _noting_base(original):
    def build_base_or_note(lto_symbol, compile_func, builder, extra_files=None):
        notes = getattr(_local, "notes", None)
        if notes is None:
            return original(lto_symbol, compile_func, builder, extra_files)
        path = os.path.join(_wp_build.get_lto_cache_dir(), f"{_wp_build.hash_symbol(lto_symbol)[:_key_length()]}.lto")
        if os.path.exists(path):  # a cache hit costs nothing: let Warp read it
            return original(lto_symbol, compile_func, builder, extra_files)
        name, arguments = _local.call
        notes.setdefault(lto_symbol, Request(lto_symbol, name, arguments))
        # the code generated while noting is thrown away: any bytes of the right kind will do
        return (True, b"", *[0 if ext == ".meta" else b"" for ext in (extra_files or {})])

    build_base_or_note.__wrapped_by_warpgym__ = True
    return build_base_or_note


def _key_length() -> int:
    return getattr(_wp_build, "LTO_CACHE_KEY_LENGTH", 64)


def _install() -> None:
    base = getattr(_wp_build, "_build_lto_base", None)
    if base is None or not all(hasattr(_wp_build, n) for n in (*_BUILDERS, "get_lto_cache_dir", "hash_symbol")):
        return
    for name in _BUILDERS:
        fn = getattr(_wp_build, name)
        if not getattr(fn, "__wrapped_by_warpgym__", False):
            setattr(_wp_build, name, _noting_builder(name, fn))
    # compile_log may have wrapped it already (to time it): wrap its wrapper, so the timing still counts real builds
    _originals["base"] = base
    _wp_build._build_lto_base = _noting_base(base)


_install()


def _links_lto(module) -> bool:
    sources = [k.adj.source for k in module.kernels.values()]
    sources += [f.adj.source for f in getattr(module, "functions", {}).values() if getattr(f, "adj", None)]
    return any(b in (src or "") for src in sources for b in LTO_BUILTINS)


def lto_requests(module, arch: int, block_dim: int | None = None) -> list[Request]:
    """The LTO objects that compiling ``module`` for ``sm_<arch>`` at ``block_dim`` would build
    because the cache lacks them; empty when it links none or libmathdx is off."""
    if not _originals or not _links_lto(module):
        return []
    block_dim = block_dim if block_dim is not None else module.options["block_dim"]
    options = module.resolve_options(wp.config, block_dim=block_dim) | {"output_arch": arch}
    module.get_module_hash(block_dim)  # code generation reads the variant's hasher
    _local.notes = notes = {}
    try:
        module._run_codegen(options, False)
    except Exception:  # noqa: BLE001  (a module whose code cannot be generated fails again, and reports, when it compiles)
        pass
    finally:
        _local.notes = _local.call = None
    return list(notes.values())


class _Scratch:
    """What Warp's LTO builders write into besides the cache: a ModuleBuilder's LTO fields."""

    def __init__(self):
        self.ltoirs, self.ltoirs_decl, self.fatbins, self.shared_memory_bytes = {}, {}, {}, {}


def build(request: Request) -> None:
    """Run one noted build in this process (into Warp's LTO cache)."""
    getattr(_wp_build, request.builder)(**request.arguments, builder=_Scratch())


# The child imports Warp alone (not warpgym, whose import pulls in torch and Newton) and sets the
# cache folder after wp.init(), which would otherwise append Warp's version to it.
_CHILD = """
import pickle, sys
import warp as wp
import warp._src.build as build
job = pickle.loads(sys.stdin.buffer.read())
wp.config.quiet = True
wp.init()
wp.config.kernel_cache_dir = job["kernel_cache_dir"]
class Scratch:
    ltoirs, ltoirs_decl, fatbins, shared_memory_bytes = {}, {}, {}, {}
getattr(build, job["builder"])(**job["arguments"], builder=Scratch())
"""


class ChildBuild:
    """One LTO object being built in a child process. ``wait()`` returns whether it was built, and
    logs the build (``compile_log.lto_builds``) the first time."""

    def __init__(self, request: Request):
        self.request = request
        self.start = time.time()
        self._ok: bool | None = None
        env = {**os.environ, "CUDA_VISIBLE_DEVICES": ""}  # the child needs no GPU: it holds no CUDA context
        self._child = subprocess.Popen([sys.executable, "-c", _CHILD], stdin=subprocess.PIPE,
                                       stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env)
        self._child.stdin.write(pickle.dumps({"builder": request.builder, "arguments": request.arguments,
                                              "kernel_cache_dir": wp.config.kernel_cache_dir}))
        self._child.stdin.close()
        self._lock = threading.Lock()

    def wait(self) -> bool:
        with self._lock:
            if self._ok is None:
                error = self._child.stderr.read().decode(errors="replace")
                self._ok = self._child.wait() == 0
                compile_log.note_lto_build(self.request.symbol, self.start, time.time() - self.start,
                                           None if self._ok else error.strip().splitlines()[-1:])
            return self._ok


_started: dict[str, ChildBuild] = {}


def start_builds(requests: list[Request]) -> list[ChildBuild]:
    """A child process for each object not already being built by this process."""
    for r in requests:
        if r.symbol not in _started:
            _started[r.symbol] = ChildBuild(r)
    return [_started[r.symbol] for r in requests]
