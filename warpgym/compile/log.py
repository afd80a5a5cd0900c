"""Where a cold start's compile time goes: one record per Warp module this process compiled.

Warp compiles a module in three steps: Python code generation, held under one process-wide lock
(``_codegen_lock``); inside it, the libmathdx LTO objects that tile solvers and GEMMs link
(cuSolverDx, cuBLASDx); then NVRTC (or Clang on the CPU), outside the lock. A record splits the
module's wall time into those steps plus the wait for the lock, so a timeline shows whether the
compiles ran side by side or queued behind one another. ``benchmarks/speed/cold_start.py`` prints it.

The split comes from wrapping Warp's private build functions (``Module._run_codegen``,
``build._build_lto_base``, ``build.build_cuda``/``build_cpu``) of the pinned warp-lang 1.19; in a
Warp without one of them that column stays at zero and the rest still adds up.
"""

from __future__ import annotations

import functools
import threading
import time

import warp._src.build as _wp_build
import warp._src.codegen as _wp_codegen
import warp._src.context as _wp_context

_local = threading.local()
_records: list[dict] = []
_records_lock = threading.Lock()
lto_builds: list[dict] = []  # libmathdx objects built in child processes (warpgym.compile.mathdx)
_PHASES = ("lock_wait_s", "codegen_s", "lto_s", "native_s")


def begin(module, block_dim) -> dict:
    """Start the record of a compile in this thread; ``end`` closes it."""
    rec = {"module": module.name, "block_dim": block_dim, "thread": threading.current_thread().name,
           "start": time.time(), **dict.fromkeys(_PHASES, 0.0)}
    rec["_t0"], rec["_outer"] = time.perf_counter(), getattr(_local, "record", None)
    _local.record = rec
    return rec


def end(rec: dict, compiled: bool) -> None:
    """Close ``rec``; keep it if the module was compiled rather than read from the cache."""
    rec["seconds"] = time.perf_counter() - rec.pop("_t0")
    _local.record = rec.pop("_outer")
    if compiled:
        with _records_lock:
            _records.append(rec)


def _add(phase: str, seconds: float) -> None:
    rec = getattr(_local, "record", None)
    if rec is not None:
        rec[phase] += seconds


def _timed(phase: str, fn):
    @functools.wraps(fn)
    def timed(*args, **kwargs):
        start = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            _add(phase, time.perf_counter() - start)

    timed.__wrapped_by_warpgym__ = True
    return timed


def _codegen_timed(fn):
    lock = getattr(_wp_codegen, "_codegen_lock", None)

    @functools.wraps(fn)
    def run_codegen(*args, **kwargs):
        start = time.perf_counter()
        if lock is None:
            return fn(*args, **kwargs)
        with lock:  # re-entrant: taking it first tells the wait from the work
            got = time.perf_counter()
            _add("lock_wait_s", got - start)
            try:
                return fn(*args, **kwargs)
            finally:
                _add("codegen_s", time.perf_counter() - got)

    run_codegen.__wrapped_by_warpgym__ = True
    return run_codegen


def _install() -> None:
    targets = [(_wp_context.Module, "_run_codegen", _codegen_timed),
               (_wp_build, "_build_lto_base", functools.partial(_timed, "lto_s")),
               (_wp_build, "build_cuda", functools.partial(_timed, "native_s")),
               (_wp_build, "build_cpu", functools.partial(_timed, "native_s"))]
    for owner, name, wrap in targets:
        fn = getattr(owner, name, None)
        if fn is not None and not getattr(fn, "__wrapped_by_warpgym__", False):
            setattr(owner, name, wrap(fn))


_install()


def note_lto_build(symbol: str, start: float, seconds: float, error) -> None:
    with _records_lock:
        lto_builds.append({"symbol": symbol, "start": start, "seconds": seconds, "error": error})


def lto_builds_since(since: float = 0.0) -> list[dict]:
    return [{**b, "start": round(b["start"] - since, 3), "seconds": round(b["seconds"], 3)} for b in list(lto_builds)]


def compiled_modules() -> list[tuple[str, float]]:
    """(module name, seconds) for every Warp module this process compiled rather than found in the
    kernel cache, in the order they finished."""
    return [(r["module"], r["seconds"]) for r in list(_records)]


def compile_trace(since: float = 0.0) -> list[dict]:
    """Every compile record: module, block_dim, thread, start (seconds after ``since``, a
    ``time.time()``), seconds, and their split: lock_wait_s, codegen_s (LTO included), lto_s,
    native_s; load_s is the rest (reading the binary back and loading it on the device)."""
    out = []
    for r in _records:
        row = {k: (round(v, 3) if isinstance(v, float) else v) for k, v in r.items()}
        row["start"] = round(r["start"] - since, 3)
        row["load_s"] = round(max(r["seconds"] - r["lock_wait_s"] - r["codegen_s"] - r["native_s"], 0.0), 3)
        out.append(row)
    return out


def mark() -> tuple[int, int]:
    """A point in the log, for ``describe_compiles``."""
    return len(_records), len(lto_builds)


def describe_compiles(since: tuple[int, int] = (0, 0)) -> str:
    """One line on what was compiled since ``since`` (a ``mark()``)."""
    done, children = list(_records)[since[0]:], list(lto_builds)[since[1]:]
    if not done:
        return "every kernel came from the cache"
    first = min(r["start"] for r in done)
    last = max(r["start"] + r["seconds"] for r in done)
    slowest = max(done, key=lambda r: r["seconds"])
    lto = sum(r["lto_s"] for r in done)
    line = (f"Warp compiled {len(done)} module{'s' * (len(done) > 1)} in {last - first:.1f} s "
            f"(NVRTC {sum(r['native_s'] for r in done):.1f} s of work, code generation "
            f"{sum(r['codegen_s'] for r in done) - lto:.1f} s, libmathdx {lto:.1f} s in this process")
    if children:
        failed = sum(1 for c in children if c["error"])
        line += (f", {len(children)} libmathdx objects in {max(c['seconds'] for c in children):.1f} s in child processes"
                 + (f" ({failed} failed and were built here)" if failed else ""))
    return line + f"; slowest {slowest['seconds']:.1f} s: {slowest['module']})"
