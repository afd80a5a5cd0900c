"""A task's tables of terms into Warp functions: one function per table that calls each term's function in the
table's order (``warpgym.tasks.terms`` declares the tables and fills their parameters). The kernels of the step call these, so every term runs
inside the step's one graph, and a user's term is compiled into it like warpgym's own.

Each generated function's source is written out (``source_of``) and compiled under a name of its own, registered
with ``linecache`` so that Warp reads it as it reads a file; the same table always gives the same source, so Warp's
kernel cache serves it across processes. Parameters reach the terms through one struct per table, a field per term
that has parameters, named after the term.

Shapes: N worlds; K terms of a table.
"""

from __future__ import annotations

import hashlib
import keyword
import linecache

import warp as wp

from kernels.common import Intervals, ObsLayout


_MADE: dict[str, tuple] = {}


def _params_struct(name: str, terms) -> type:
    """The struct of a table's parameters: a field per term whose function takes a parameter struct."""
    fields = {term: ptype for term, _, ptype in terms if ptype is not None}
    if not fields:  # Warp has no empty struct
        fields = {"unused": int}
    cls = type(name, (), {"__annotations__": fields, "__module__": __name__, "__qualname__": name})
    return wp.struct(cls)


def _compile(tag: str, source: str, scope: dict):
    """The function defined by ``source``, read by Warp as if from a file of its own."""
    digest = hashlib.sha256(source.encode()).hexdigest()[:16]
    filename = f"<warpgym-{tag}-{digest}>"
    linecache.cache[filename] = (len(source), None, source.splitlines(True), filename)
    exec(compile(source, filename, "exec"), scope)  # noqa: S102  (our own generated source, never a file's)
    fn = scope[tag]
    fn.__module__ = f"warpgym_terms_{digest}"
    return wp.func(fn)


def _check(terms) -> None:
    for name, func, _ in terms:
        if not name.isidentifier() or keyword.iskeyword(name):
            raise ValueError(f"term name {name!r} is not a Python identifier: name terms like variables, e.g. "
                             "'feet_air_time'")
        if not isinstance(func, wp.Function):
            raise TypeError(f"term {name!r}: its function {func!r} is not a @wp.func")


def _call(k: int, name: str, ptype, *args: str) -> str:
    return f"f{k}({', '.join(args)}{', tp.' + name if ptype is not None else ''})"


def reward_sum(env_type, terms) -> tuple[type, object, str]:
    """``(Params, func, source)``: ``func(env, w, tp: Params, weights, dt, values) -> float`` writes each term's
    ``weight * dt * value`` into ``values[w, k]`` (0 where the weight is 0, which skips the term, or where the value
    is not finite) and returns their sum. ``terms``: ``[(name, wp.func, params struct or None)]``."""
    lines = ["def rewards(env: Env, w: int, tp: Params, weights: wp.array[float], dt: float, "
             "values: wp.array2d[float]) -> float:",
             "    total = float(0.0)"]
    for k, (name, _, ptype) in enumerate(terms):
        lines += [f"    # {name}",
                  f"    v{k} = float(0.0)",
                  f"    if weights[{k}] != 0.0:",
                  f"        v{k} = {_call(k, name, ptype, 'env', 'w')} * weights[{k}] * dt",
                  f"        if not wp.isfinite(v{k}):",
                  f"            v{k} = 0.0",
                  f"    values[w, {k}] = v{k}",
                  f"    total += v{k}"]
    lines.append("    return total")
    return _made("rewards", env_type, terms, lines)


def termination_flags(env_type, terms, time_outs: list[bool]) -> tuple[type, object, str]:
    """``(Params, func, source)``: ``func(env, w, tp: Params) -> wp.vec2i``, (any failure, any time-out) of the
    table's terminations; ``time_outs[k]``: term k ends an episode as a time-out."""
    lines = ["def terminations(env: Env, w: int, tp: Params) -> wp.vec2i:",
             "    failed = int(0)",
             "    timed_out = int(0)"]
    for k, ((name, _, ptype), time_out) in enumerate(zip(terms, time_outs)):
        flag = "timed_out" if time_out else "failed"
        lines += [f"    if {_call(k, name, ptype, 'env', 'w')}:  # {name}",
                  f"        {flag} = 1"]
    lines.append("    return wp.vec2i(failed, timed_out)")
    return _made("terminations", env_type, terms, lines)


def observation_group(env_type, group: str, terms) -> tuple[type, object, str]:
    """``(Params, func, source)``: ``func(env, w, rng, fresh, tp: Params, layout: ObsLayout, out) -> rng`` writes
    world ``w``'s row of the group, each term's entries in turn, noise, clip and scale as ``layout`` gives them; a
    term with history writes its last ``history`` frames, oldest first, and ``fresh`` (the world's first observation
    since its reset) fills them all with this one, as Isaac Lab's and mjlab's history buffers do. Warp's draws
    advance the state passed in: the function returns it, for the caller to go on drawing from."""
    tag = f"observe_{group}"
    lines = [f"def {tag}(env: Env, w: int, rng: wp.uint32, fresh: int, tp: Params, layout: ObsLayout, "
             "out: wp.array2d[float]) -> wp.uint32:",
             "    at = int(0)"]
    for k, (name, _, ptype) in enumerate(terms):
        lines += [f"    # {name}",
                  f"    n{k} = layout.size[{k}]",
                  f"    h{k} = layout.history[{k}]",
                  f"    for i in range(n{k}):",
                  f"        x = {_call(k, name, ptype, 'env', 'w', 'i')}",
                  f"        if layout.noise[{k}] != 0.0:",
                  f"            x = x + wp.randf(rng, -layout.noise[{k}], layout.noise[{k}])",
                  f"        if layout.clip[{k}] != 0:",
                  f"            x = wp.clamp(x, layout.lo[{k}], layout.hi[{k}])",
                  f"        x = x * layout.scale[{k}]",
                  f"        if h{k} == 1:",
                  f"            out[w, at + i] = x",
                  f"        else:",
                  f"            base = layout.hist_at[{k}]",
                  f"            for j in range(h{k}):",
                  f"                if fresh != 0 or j == h{k} - 1:",
                  f"                    layout.hist[w, base + j * n{k} + i] = x",
                  f"                else:",
                  f"                    layout.hist[w, base + j * n{k} + i] = layout.hist[w, base + (j + 1) * n{k} + i]",
                  f"                out[w, at + j * n{k} + i] = layout.hist[w, base + j * n{k} + i]",
                  f"    at = at + n{k} * h{k}"]
    lines.append("    return rng")
    return _made(tag, env_type, terms, lines)


def event_calls(env_type, mode: str, terms) -> tuple[type, object, str]:
    """``(Params, func, source)``: ``func(env, w, rng, tp: Params) -> rng`` runs the ``mode`` events (startup or
    reset) for world ``w`` in turn, each drawing from the state the one before it left."""
    tag = f"events_{mode}"
    lines = [f"def {tag}(env: Env, w: int, rng: wp.uint32, tp: Params) -> wp.uint32:"]
    for k, (name, _, ptype) in enumerate(terms):
        lines.append(f"    rng = {_call(k, name, ptype, 'env', 'w', 'rng')}  # {name}")
    lines.append("    return rng")
    return _made(tag, env_type, terms, lines)


def interval_calls(env_type, terms) -> tuple[type, object, str]:
    """``(Params, func, source)``: ``func(env, w, rng, live, tp: Params, iv: Intervals, dt) -> rng`` counts each
    interval event's timer down by ``dt``; one that falls due draws its next interval and, where ``live`` (the
    world's state is finite), runs (mjlab's event manager: due below 1e-6 s)."""
    lines = ["def events_interval(env: Env, w: int, rng: wp.uint32, live: int, tp: Params, iv: Intervals, "
             "dt: float) -> wp.uint32:"]
    for k, (name, _, ptype) in enumerate(terms):
        lines += [f"    # {name}",
                  f"    iv.left[w, {k}] = iv.left[w, {k}] - dt",
                  f"    if iv.left[w, {k}] < 1.0e-6:",
                  f"        iv.left[w, {k}] = wp.randf(rng, iv.lo[{k}], iv.hi[{k}])",
                  "        if live != 0:",
                  f"            rng = {_call(k, name, ptype, 'env', 'w', 'rng')}"]
    lines.append("    return rng")
    return _made("events_interval", env_type, terms, lines)


def _made(tag: str, env_type, terms, lines: list[str]) -> tuple[type, object, str]:
    """The table's parameter struct and function, made once per source (the same table's function is Warp's same
    function, its kernels compiled once in a process)."""
    _check(terms)
    source = "\n".join(lines) + "\n"
    key = tag, env_type, source, tuple((n, id(f), p) for n, f, p in terms)
    if key not in _MADE:
        _MADE[key] = _finish(tag, env_type, terms, source)
    return _MADE[key]


def _finish(tag: str, env_type, terms, source: str) -> tuple[type, object, str]:
    # named by what it holds, so that two tables' structs never share a name and one table's always has the same
    shape = source + "".join(f"{n}:{_struct_key(p)};" for n, _, p in terms if p is not None)
    params = _params_struct(f"{tag}_{hashlib.sha256(shape.encode()).hexdigest()[:16]}", terms)
    scope = {"wp": wp, "Env": env_type, "Params": params, "ObsLayout": ObsLayout, "Intervals": Intervals,
             **{f"f{k}": func for k, (_, func, _) in enumerate(terms)}}
    return params, _compile(tag, source, scope), source


def _struct_key(struct) -> str:
    cls = getattr(struct, "cls", None)
    return f"{cls.__module__}.{cls.__qualname__}" if cls is not None else str(getattr(struct, "key", struct))
