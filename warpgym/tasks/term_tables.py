"""docs/tasks.md's tables of the legged tasks' terms, printed from the tasks' own tables (``python -m
warpgym.tasks.term_tables``; ``benchmarks.doc_tables`` writes and checks the page's block from it): each reward term's
function, weight per task and parameters, each observation term's entries, noise and scale per group, each
termination and each event."""

from __future__ import annotations

import sys

from warpgym.tasks.legged import LEGGED
from warpgym.tasks.terms import PerJoint, Terms

# the four tasks in the page's column order, and their headings
COLUMNS = (("Go1VelocityFlat-v0", "Go1 flat"), ("Go1VelocityRough-v0", "Go1 rough"), ("G1VelocityFlat-v0", "G1 flat"),
           ("G1VelocityRough-v0", "G1 rough"))
SIZES = {"_joints": "joints", "_actions": "actions", "_feet": "feet", "_forces": "3 x feet", "_scan": "scan rays"}


def _value(value) -> str:
    if isinstance(value, PerJoint):
        return "per joint"
    if isinstance(value, float):
        return f"{value:.4g}"
    if isinstance(value, tuple):
        return "(" + ", ".join(_value(v) for v in value) + ")"
    return str(value)


def _params(term) -> str:
    return ", ".join(f"{k}={_value(v)}" for k, v in term.params) or "-"


def _names(tables: list[Terms]) -> list[str]:
    """Every term of the tables, in the order of the longest table, then of the others."""
    out: list[str] = []
    for table in sorted(tables, key=len, reverse=True):
        out += [n for n in table if n not in out]
    return out


def _tasks_with(have: list) -> str:
    """The columns' tasks whose table has the term ("all", or their names)."""
    names = [h for (_, h), term in zip(COLUMNS, have) if term is not None]
    return "all" if len(names) == len(COLUMNS) else ", ".join(names) or "-"


def rewards() -> str:
    tasks = [LEGGED[name] for name, _ in COLUMNS]
    lines = ["| reward term | function | " + " | ".join(h for _, h in COLUMNS) + " | parameters |",
             "|---|---|" + "---:|" * len(COLUMNS) + "---|"]
    for name in _names([t.rewards for t in tasks]):
        have = [t.rewards.get(name) for t in tasks]
        first = next(term for term in have if term is not None)
        weights = [f"{term.weight:g}" if term is not None and term.weight else "-" for term in have]
        params = {_params(term) for term in have if term is not None}
        lines.append(f"| `{name}` | `{first.func.key}` | " + " | ".join(weights) + " | "
                     + "; ".join(sorted(params)) + " |")
    return "\n".join(lines)


def observations() -> str:
    tasks = [LEGGED[name] for name, _ in COLUMNS]
    lines = ["| observation term | function | entries | noise (policy) | scale | policy | critic |",
             "|---|---|---|---:|---:|---|---|"]
    for name in _names([t.critic_obs for t in tasks]):
        policy = [t.policy_obs.get(name) for t in tasks]
        critic = [t.critic_obs.get(name) for t in tasks]
        term = next(x for x in policy + critic if x is not None)
        size = term.size if isinstance(term.size, int) else SIZES.get(term.size.__name__, term.size.__name__)
        noise = {f"{x.noise:g}" for x in policy if x is not None} or {"-"}
        scale = {f"{x.scale:g}" for x in policy + critic if x is not None}
        where = [_tasks_with(group) for group in (policy, critic)]
        lines.append(f"| `{name}` | `{term.func.key}` | {size} | {', '.join(sorted(noise))} | "
                     f"{', '.join(sorted(scale))} | {where[0]} | {where[1]} |")
    return "\n".join(lines)


def terminations() -> str:
    tasks = [LEGGED[name] for name, _ in COLUMNS]
    lines = ["| termination | function | ends as | parameters | tasks |", "|---|---|---|---|---|"]
    for name in _names([t.terminations for t in tasks]):
        have = [t.terminations.get(name) for t in tasks]
        term = next(x for x in have if x is not None)
        where = _tasks_with(have)
        lines.append(f"| `{name}` | `{term.func.key}` | {'time-out' if term.time_out else 'failure'} | "
                     f"{_params(term)} | {where} |")
    return "\n".join(lines)


def events() -> str:
    tasks = [LEGGED[name] for name, _ in COLUMNS]
    lines = ["| event | function | runs | parameters | tasks |", "|---|---|---|---|---|"]
    for name in _names([t.events for t in tasks]):
        have = [t.events.get(name) for t in tasks]
        term = next(x for x in have if x is not None)
        runs = {"startup": "once, when the env is built", "reset": "at each reset"}.get(term.mode)
        if runs is None:
            runs = f"every {term.interval[0]:g}-{term.interval[1]:g} s"
        params = {_params(x) for x in have if x is not None}
        lines.append(f"| `{name}` | `{term.func.key}` | {runs} | {'; '.join(sorted(params))} | {_tasks_with(have)} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    print(rewards() + "\n\n" + observations() + "\n\n" + terminations() + "\n\n" + events())
    return 0


if __name__ == "__main__":
    sys.exit(main())
