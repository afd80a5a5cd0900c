"""Task names as the command line, Gymnasium and the checkpoints write them: ``"Go1VelocityFlat-v0"``, or
``"my_tasks:MyGo1-v0"``, Gymnasium's form for an env defined in a user's module, which is imported first so that it
registers its tasks (``warpgym.tasks.registry.register``)."""

from __future__ import annotations

import importlib


def imported(name: str) -> str:
    """The task's own name, its module (before a ':') imported; a module that cannot be imported is one line."""
    if not isinstance(name, str) or ":" not in name:
        return name
    module, _, short = name.partition(":")
    try:
        importlib.import_module(module)
    except ImportError as e:
        raise ValueError(f"task {name!r}: its module {module!r} cannot be imported ({e}); put it on the path "
                         "(PYTHONPATH, or run from its folder)") from None
    return short


def recorded(name: str, flag: str = "--import") -> str:
    """A task name read from a run's files: a user's task only once its module is imported (by the command's
    ``--import MODULE``, or by the caller), since nothing read from a file runs code. Returns the name."""
    import sys  # noqa: PLC0415

    if isinstance(name, str) and ":" in name:
        module = name.partition(":")[0]
        if module not in sys.modules:
            raise ValueError(f"the run trained {name!r}, a task of the module {module!r}, which a run's files never "
                             f"import: pass {flag} {module}")
    return name


def import_modules(modules: list[str]) -> None:
    """The modules a command's ``--import`` names, imported (they register their tasks); one line if one fails."""
    for module in modules or ():
        imported(f"{module}:")
