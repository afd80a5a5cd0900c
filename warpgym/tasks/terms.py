"""Tasks as tables of terms: a task's rewards, observations, terminations and events, each declared once as a term (a
Warp function, its weight or noise, clip and scale, or when it runs, its parameters by name) in an ordered table
(``Terms``). Everything
else comes from the tables: the functions the step's kernels call (``warpgym.tasks.dispatch``), the parameter structs,
the observation's layout (sizes and offsets, ``layout``), the export contract and the docs' term tables.

A term's function is a ``@wp.func`` over the state its family names (the legged tasks': ``kernels.legged.params.
LeggedEnv``): ``(env, w)`` for a reward (a float) or a termination (a bool), ``(env, w, i)`` for entry ``i`` of
an observation, ``(env, w, rng) -> rng`` for an event (it draws from ``rng`` and returns the state after its
draws); a parameter struct as its last argument, when it has parameters. A ``wp.vec2`` parameter is a (low, high)
range, checked as one. A user's own term is such a
function in the user's own module::

    @wp.struct
    class Apart:
        min_distance: float

    @wp.func
    def feet_apart(env: LeggedEnv, w: int, p: Apart) -> float:
        ...

    envs = gym.make_vec("warpgym/Go1VelocityFlat-v0", num_envs=4096,
                        rewards={"feet_apart": Reward(feet_apart, weight=-1.0, params={"min_distance": 0.2})})

A table's changes (``Terms.changed``) add a term, replace one, change its fields (``{"pose": {"weight": 2.0}}``, or
a bare number for a reward's weight) or drop it (``None``).
"""

from __future__ import annotations

import math
import re
import inspect
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from typing import Any, Callable

import numpy as np


def _frozen(params) -> tuple:
    if params is None:
        return ()
    if isinstance(params, Mapping):
        return tuple(params.items())
    return tuple(params)


@dataclass(frozen=True)
class Reward:
    """A reward term: ``weight * dt * func(env, w[, params])`` a step (0 weight: not computed, as in mjlab)."""

    func: Any
    weight: float
    params: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "params", _frozen(self.params))


@dataclass(frozen=True)
class Observation:
    """An observation term: ``size`` entries ``func(env, w, i[, params])``, each with uniform noise in [-noise,
    noise] (the policy's; none when a task turns noise off), clamped into ``clip`` (low, high) when given, then
    times ``scale`` (mjlab's order). ``size``: a number, or a function of the env's ``Dims`` (joints, actions,
    feet, scan rays). ``history``: the last that many observations of the term, oldest first (``size x history``
    entries; after a reset every frame is the first observation). ``what``: the entry's meaning in the export
    contract (default: the function's docstring)."""

    func: Any
    size: int | Callable
    noise: float = 0.0
    clip: tuple | None = None
    scale: float = 1.0
    params: tuple = ()
    what: str = ""
    history: int = 1

    def __post_init__(self):
        object.__setattr__(self, "params", _frozen(self.params))


@dataclass(frozen=True)
class Termination:
    """A termination: ``func(env, w[, params])`` true ends the episode, as a failure or (``time_out``) a truncation
    that a learner bootstraps."""

    func: Any
    time_out: bool = False
    params: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "params", _frozen(self.params))


EVENT_MODES = ("startup", "reset", "interval")


@dataclass(frozen=True)
class Event:
    """An event (mjlab's event terms): ``func(env, w, rng[, params]) -> rng`` run for a world once when the env is
    built (``mode="startup"``: a model field's or the task state's randomisation, then MuJoCo Warp's ``set_const``),
    at each of its resets (``"reset"``: its start pose), or every ``interval`` (low, high) seconds, drawn uniformly
    per world and again at its resets (``"interval"``: pushes). A table's events of one mode run in its order."""

    func: Any
    mode: str
    params: tuple = ()
    interval: tuple | None = None

    def __post_init__(self):
        object.__setattr__(self, "params", _frozen(self.params))


TERM_TYPES = {"reward": Reward, "observation": Observation, "termination": Termination, "event": Event}


def of_mode(table: Terms, *modes: str) -> Terms:
    """The events of ``table`` run in ``modes``, in the table's order (``of_mode(task.events, "reset")``: the
    nominal robot, no randomisation or pushes)."""
    return Terms("event", [(n, t) for n, t in table.items() if t.mode in modes])


class Terms(Mapping):
    """An ordered, immutable table of terms of one kind, by name."""

    def __init__(self, kind: str, items=()):
        self.kind = kind
        self._items = tuple((str(n), t) for n, t in (items.items() if isinstance(items, Mapping) else items))
        cls = TERM_TYPES[kind]
        for name, term in self._items:
            if not isinstance(term, cls):
                raise TypeError(f"{kind} term {name!r} is {term!r}: declare it as {cls.__name__}(func, ...)")

    def __getitem__(self, name):
        for n, t in self._items:
            if n == name:
                return t
        raise KeyError(name)

    def __iter__(self):
        return (n for n, _ in self._items)

    def __len__(self):
        return len(self._items)

    def __eq__(self, other):
        return isinstance(other, Terms) and self.kind == other.kind and self._items == other._items

    def __hash__(self):
        return hash((self.kind, self._items))

    def __repr__(self):
        return f"Terms({self.kind!r}, [{', '.join(self)}])"

    def changed(self, changes, where: str) -> Terms:
        """This table with ``changes`` ({name: term, a dict of the term's fields, a reward's weight, or None to drop
        it}) made; ``where`` names the table in an error."""
        if isinstance(changes, Terms):
            return changes
        if not isinstance(changes, Mapping):
            raise ValueError(f"{where}={changes!r} must map term names to terms, e.g. "
                             f"{{'name': {TERM_TYPES[self.kind].__name__}(func, ...)}}")
        items = dict(self._items)
        for name, change in changes.items():
            if change is None:
                if name not in items:
                    raise ValueError(f"{where}: no term {name!r} to drop; its terms are {list(items)}")
                del items[name]
            elif isinstance(change, TERM_TYPES[self.kind]):
                items[name] = change
            elif name not in items:
                raise ValueError(f"{where}: no term {name!r}; its terms are {list(items)} (a new term is a "
                                 f"{TERM_TYPES[self.kind].__name__}(func, ...))")
            elif self.kind == "reward" and _is_number(change):
                items[name] = replace(items[name], weight=float(change))
            elif isinstance(change, Mapping):
                known = {f.name for f in fields(items[name]) if f.init}
                wrong = sorted(set(change) - known)
                if wrong:
                    raise ValueError(f"{where}: {name!r} has no field(s) {wrong}: its fields are {sorted(known)}")
                change = dict(change)
                if "params" in change:  # the parameters given are changed, the others kept
                    change["params"] = {**dict(items[name].params), **dict(change["params"])}
                items[name] = replace(items[name], **change)
            else:
                raise ValueError(f"{where}: {name!r}={change!r} must be a {TERM_TYPES[self.kind].__name__}, a dict "
                                 "of its fields" + (", a weight" if self.kind == "reward" else "") + " or None")
        return Terms(self.kind, items)


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def _is_range(v) -> bool:
    return isinstance(v, (tuple, list)) and len(v) == 2 and all(_is_number(x) for x in v) and v[0] <= v[1]


# ---------------------------------------------------------------------------------------------------------------
# parameters: a value per field of the term's parameter struct


class PerJoint:
    """A parameter with a value per actuated joint, from (pattern, value) pairs, each pattern matched in full
    against the joint's name without its entity prefix, one pattern per joint (mjlab's
    ``resolve_matching_names_values``)."""

    def __init__(self, pairs):
        self.pairs = tuple((str(p), float(v)) for p, v in (pairs.items() if isinstance(pairs, Mapping) else pairs))

    def __eq__(self, other):
        return isinstance(other, PerJoint) and self.pairs == other.pairs

    def __hash__(self):
        return hash(self.pairs)

    def __repr__(self):
        return f"PerJoint({self.pairs!r})"

    def resolve(self, joints: list[str], where: str) -> np.ndarray:
        out = np.full(len(joints), np.nan)
        for j, joint in enumerate(joints):
            short = joint.rsplit("/", 1)[-1]
            hits = [(p, v) for p, v in self.pairs if re.fullmatch(p, short)]
            if len(hits) > 1:
                raise ValueError(f"{where}: joint {short!r} matches more than one pattern {[p for p, _ in hits]}; "
                                 "make the patterns exclusive")
            if hits:
                out[j] = hits[0][1]
        missing = [joints[j].rsplit("/", 1)[-1] for j in np.flatnonzero(np.isnan(out))]
        if missing:
            raise ValueError(f"{where} gives no value for joint(s) {missing}: add a pattern that matches them")
        return out.astype(np.float32)


def _return_type(func, where: str):
    """A term's declared return type, string annotations resolved as Warp resolves them when it makes the function
    (its module's names, then the function's closure's), so a term Warp took is never refused here."""
    closure = inspect.getclosurevars(func.func).nonlocals
    return inspect.get_annotations(func.func, eval_str=True, locals=closure).get("return")


def signature(term, kind: str, where: str):
    """The parameter struct a term's function takes (None: none), its arguments checked against the kind's form."""
    import warp as wp  # noqa: PLC0415

    func = term.func
    if not isinstance(func, wp.Function):
        raise TypeError(f"{where}: {func!r} is not a @wp.func: decorate the term's function with @wp.func")
    args = list(func.input_types.items())
    lead = 3 if kind in ("observation", "event") else 2
    form = {"observation": "(env, w, i[, params])", "event": "(env, w, rng[, params]) -> rng"}.get(
        kind, "(env, w[, params])")
    # the return type as Warp resolves it: a module with ``from __future__ import annotations`` holds strings
    if kind == "event" and (len(args) < 3 or args[2][1] is not wp.uint32 or _return_type(func, where) is not wp.uint32):
        raise TypeError(f"{where}: {func.key} must take and return the random state: an event's function is "
                        f"{form}, rng a wp.uint32")
    if len(args) not in (lead, lead + 1):
        raise TypeError(f"{where}: {func.key} takes {[a for a, _ in args]}; a {kind} term's function takes {form}")
    if len(args) == lead:
        return None
    ptype = args[-1][1]
    if not hasattr(ptype, "vars"):
        raise TypeError(f"{where}: {func.key}'s last argument {args[-1][0]!r} is not a @wp.struct of parameters")
    return ptype


def param_struct(term, kind: str, where: str, joints: list[str], device: str):
    """The term's parameter struct, filled from its ``params`` by name (None when its function takes none)."""
    import warp as wp  # noqa: PLC0415

    ptype = signature(term, kind, where)
    given = dict(term.params)
    if ptype is None:
        if given:
            raise ValueError(f"{where}: {term.func.key} takes no parameters, given {sorted(given)}")
        return None
    names = list(ptype.vars)
    wrong, missing = sorted(set(given) - set(names)), [n for n in names if n not in given]
    if wrong or missing:
        raise ValueError(f"{where}: {term.func.key}'s parameters are {names}; "
                         + (f"unknown {wrong}" if wrong else "") + ("; " if wrong and missing else "")
                         + (f"missing {missing}" if missing else ""))
    out = ptype()
    for name, var in ptype.vars.items():
        value = given[name]
        if isinstance(value, PerJoint):
            value = value.resolve(joints, f"{where} {name}")
        if wp.types.is_array(var.type):
            if np.ndim(value) != 1:
                raise ValueError(f"{where}: {name}={value!r} must hold a value per entry: a sequence, or "
                                 "PerJoint(((pattern, value), ...)) for a value per joint")
            value = wp.array(np.asarray(value, dtype=wp.dtype_to_numpy(var.type.dtype)),
                             dtype=var.type.dtype, device=device)
        elif var.type in (int, wp.int32):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ValueError(f"{where}: {name}={value!r} must be an integer")
            value = int(value)
        elif var.type in (float, wp.float32):
            if not _is_number(value):
                raise ValueError(f"{where}: {name}={value!r} must be a finite number")
            value = float(value)
        elif var.type is wp.vec2:  # a (low, high) range
            if not _is_range(value):
                raise ValueError(f"{where}: {name}={value!r} must be a (low, high) range of finite numbers with "
                                 "low <= high, e.g. (-0.5, 0.5)")
            value = wp.vec2(*value)
        else:
            value = var.type(*value) if isinstance(value, (tuple, list)) else value
        setattr(out, name, value)
    return out


@dataclass(frozen=True)
class Dims:
    """What an observation term's size may depend on."""

    joints: int
    actions: int
    feet: int
    scan: int  # rays of the height scan (0: none)


def sizes(table: Terms, dims: Dims, where: str) -> list[int]:
    out = []
    for name, term in table.items():
        n = term.size(dims) if callable(term.size) else term.size
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"{where}: {name!r} has size {n!r}; an observation term has at least one entry")
        out.append(int(n))
    return out


def layout(table: Terms, dims: Dims, where: str) -> list[tuple[str, int, int, str]]:
    """The group's entries term by term: (name, offset, entries, what they hold); a term with history holds
    ``size x history`` entries."""
    out, at = [], 0
    for (name, term), n in zip(table.items(), sizes(table, dims, where)):
        what = term.what or " ".join((term.func.func.__doc__ or name).split())
        if term.history > 1:
            what += f"; its last {term.history} observations, oldest first"
        out.append((name, at, n * term.history, what))
        at += n * term.history
    return out


def validate(table: Terms, where: str) -> None:
    """Each term's fields (the struct of its parameters is checked when the env is built)."""
    for name, term in table.items():
        at = f"{where}[{name!r}]"
        signature(term, table.kind, at)
        if table.kind == "reward" and not _is_number(term.weight):
            raise ValueError(f"{at}: weight={term.weight!r} must be a finite number")
        if table.kind == "observation":
            if not _is_number(term.noise) or term.noise < 0:
                raise ValueError(f"{at}: noise={term.noise!r} must be 0 or a positive number")
            if not _is_number(term.scale):
                raise ValueError(f"{at}: scale={term.scale!r} must be a finite number")
            if isinstance(term.history, bool) or not isinstance(term.history, int) or term.history < 1:
                raise ValueError(f"{at}: history={term.history!r} must be a number of observations, 1 or more")
            if term.clip is not None and not (isinstance(term.clip, tuple) and len(term.clip) == 2
                                              and all(isinstance(c, (int, float)) for c in term.clip)
                                              and term.clip[0] <= term.clip[1]):
                raise ValueError(f"{at}: clip={term.clip!r} must be a (low, high) pair or None")
        if table.kind == "event":
            if term.mode not in EVENT_MODES:
                raise ValueError(f"{at}: mode={term.mode!r} must be one of {list(EVENT_MODES)}")
            if term.mode == "interval" and not (_is_range(term.interval) and term.interval[0] > 0):
                raise ValueError(f"{at}: interval={term.interval!r} must be (low, high) seconds between its runs, "
                                 "0 < low <= high, e.g. (1.0, 3.0)")
            if term.mode != "interval" and term.interval is not None:
                raise ValueError(f"{at}: interval={term.interval!r} is for mode='interval' events; this one's mode "
                                 f"is {term.mode!r}")


# ---------------------------------------------------------------------------------------------------------------
# a table into what the step's kernels take


def _dispatch_terms(table: Terms, where: str):
    return [(name, term.func, signature(term, table.kind, f"{where}[{name!r}]")) for name, term in table.items()]


def _filled(params_type, table: Terms, where: str, joints: list[str], device: str):
    out = params_type()
    for name, term in table.items():
        value = param_struct(term, table.kind, f"{where}[{name!r}]", joints, device)
        if value is not None:
            setattr(out, name, value)
    return out


@dataclass
class Compiled:
    """One table as the kernels take it: the generated function, its parameter struct type and value, and the
    per-term arrays (a reward table's weights, an observation group's layout)."""

    func: Any
    params_type: Any
    params: Any
    arrays: Any = None
    source: str = ""


def compile_rewards(table: Terms, env_type, joints: list[str], device: str, where: str = "rewards") -> Compiled:
    import warp as wp  # noqa: PLC0415

    from warpgym.tasks.dispatch import reward_sum  # noqa: PLC0415

    params_type, func, source = reward_sum(env_type, _dispatch_terms(table, where))
    weights = wp.array(np.array([t.weight for t in table.values()], np.float32), dtype=float, device=device)
    return Compiled(func, params_type, _filled(params_type, table, where, joints, device), weights, source)


def compile_terminations(table: Terms, env_type, joints: list[str], device: str,
                         where: str = "terminations") -> Compiled:
    from warpgym.tasks.dispatch import termination_flags  # noqa: PLC0415

    params_type, func, source = termination_flags(env_type, _dispatch_terms(table, where),
                                                  [bool(t.time_out) for t in table.values()])
    return Compiled(func, params_type, _filled(params_type, table, where, joints, device), None, source)


def compile_observations(table: Terms, group: str, env_type, dims: Dims, joints: list[str], device: str,
                         noise: bool, where: str, num_envs: int) -> Compiled:
    """``noise``: False zeroes every term's noise (mjlab's play mode); ``num_envs``: the worlds a term with history
    keeps its frames for."""
    import warp as wp  # noqa: PLC0415

    from kernels.common import ObsLayout  # noqa: PLC0415
    from warpgym.tasks.dispatch import observation_group  # noqa: PLC0415

    params_type, func, source = observation_group(env_type, group, _dispatch_terms(table, where))
    terms = list(table.values())

    def arr(values, dtype=float):
        return wp.array(np.asarray(values, np.int32 if dtype == wp.int32 else np.float32), dtype=dtype, device=device)

    lay = ObsLayout()
    size = sizes(table, dims, where)
    lay.size = arr(size, wp.int32)
    lay.history = arr([t.history for t in terms], wp.int32)
    kept = [n * t.history if t.history > 1 else 0 for n, t in zip(size, terms)]
    lay.hist_at = arr(np.cumsum([0, *kept[:-1]]), wp.int32)
    lay.hist = wp.zeros((num_envs, max(sum(kept), 1)), dtype=float, device=device)
    lay.noise = arr([t.noise if noise else 0.0 for t in terms])
    lay.clip = arr([int(t.clip is not None) for t in terms], wp.int32)
    lay.lo = arr([t.clip[0] if t.clip is not None else 0.0 for t in terms])
    lay.hi = arr([t.clip[1] if t.clip is not None else 0.0 for t in terms])
    lay.scale = arr([t.scale for t in terms])
    return Compiled(func, params_type, _filled(params_type, table, where, joints, device), lay, source)


def compile_events(table: Terms, env_type, joints: list[str], device: str, num_envs: int,
                   where: str = "events") -> dict[str, Compiled]:
    """Each mode's events as the kernels take them (``EVENT_MODES`` -> ``Compiled``); the interval events' timers
    (``kernels.common.Intervals``, one row a world) are the interval mode's arrays."""
    import warp as wp  # noqa: PLC0415

    from kernels.common import Intervals  # noqa: PLC0415
    from warpgym.tasks.dispatch import event_calls, interval_calls  # noqa: PLC0415

    out = {}
    for mode in EVENT_MODES:
        sub = of_mode(table, mode)
        terms = _dispatch_terms(sub, where)
        timers = None
        if mode == "interval":
            params_type, func, source = interval_calls(env_type, terms)
            timers = Intervals()
            timers.lo = wp.array(np.array([t.interval[0] for t in sub.values()], np.float32), dtype=float,
                                 device=device)
            timers.hi = wp.array(np.array([t.interval[1] for t in sub.values()], np.float32), dtype=float,
                                 device=device)
            timers.left = wp.zeros((num_envs, max(len(sub), 1)), dtype=float, device=device)
        else:
            params_type, func, source = event_calls(env_type, mode, terms)
        out[mode] = Compiled(func, params_type, _filled(params_type, sub, where, joints, device), timers, source)
    return out


# ---------------------------------------------------------------------------------------------------------------
# a task's own terms beside its defining project's (the suite's and the robots' tasks)

OWN_TABLES = {"rewards": "reward", "terminations": "termination"}


def changed_own_tables(task, changes: dict) -> dict:
    """``changes`` with each own table it names made from the task's (``Terms.changed``)."""
    return {k: getattr(task, k).changed(v, f"{task.name}: {k}") if k in OWN_TABLES else v for k, v in changes.items()}


def validate_own_tables(task) -> None:
    """The task's ``rewards`` and ``terminations``: tables of their kind, each term's fields checked."""
    for name, kind in OWN_TABLES.items():
        table = getattr(task, name)
        if not isinstance(table, Terms) or table.kind != kind:
            raise ValueError(f"{task.name}: {name}={table!r} must be a table of {kind} terms "
                             "(warpgym.tasks.terms.Terms), e.g. {'upright': Reward(func, weight=0.1)}")
        validate(table, f"{task.name}: {name}")


def compile_own_tables(task, env_type, joints: list[str], device: str) -> tuple[Compiled, Compiled]:
    """The task's own rewards and terminations as its step kernel takes them, over ``env_type``."""
    return (compile_rewards(task.rewards, env_type, joints, device, f"{task.name}: rewards"),
            compile_terminations(task.terminations, env_type, joints, device, f"{task.name}: terminations"))
