"""The ``warpgym`` command: ``warpgym train``, ``play``, ``plot``, ``sim2sim``, ``train-with``, ``bench``, ``eval`` and
``export``.

The one package of warpgym that imports ``agents``: the commands sit on top of both sides (the
environment and the learner), so neither side imports the other. ``scripts/*.py`` in a source checkout
are the same commands."""

from __future__ import annotations

import importlib
import json
import os
import sys
import time

COMMANDS = {  # subcommand: (module, what it does)
    "train": ("train", "train PPO on a task; logs, checkpoints and the two reward plots under runs/"),
    "play": ("play", "replay a checkpoint: episode returns and speeds, an MP4 or a GIF"),
    "plot": ("plot", "reward against wall-clock time and against samples for one or more runs"),
    "sim2sim": ("sim2sim", "replay a checkpoint in warpgym and in native MuJoCo, at the training step and finer"),
    "train-with": ("train_with", "train with another learner through its adapter (rsl_rl, skrl, rl_games, sb3, rllib)"),
    "bench": ("bench", "env-steps per second of the simulation layers"),
    "eval": ("eval", "score a policy where its task is judged (Gymnasium's env, native MuJoCo) beside warpgym's env"),
    "export": ("export", "write a trained policy as ONNX and a torch.export program, with what a controller needs around it"),
}


def write_json(path: str, obj) -> None:
    """``obj`` as JSON at ``path``, whole or not at all: a crash mid-write leaves the previous file."""
    with open(path + ".tmp", "w") as f:
        json.dump(obj, f, indent=1)
    os.replace(path + ".tmp", path)


def run_task(name: str, imports: list[str]):
    """The registry entry of the task a run's files name, the modules of ``--import`` imported first (a user's
    task of ``--task MODULE:NAME`` is registered by its module, which a run's files never import themselves); a
    ValueError says what is missing."""
    from warpgym.tasks.names import import_modules, recorded  # noqa: PLC0415
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    import_modules(imports)
    return task_entry(recorded(name))


def process_start_time() -> float:
    """The wall-clock time (time.time()) at which this process started, from the kernel's record, so a
    run's clock counts the interpreter's start and every import, whichever entry point started it.
    Falls back to now where /proc is not there."""
    try:
        with open("/proc/self/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        ticks = int(fields[19])  # field 22 of proc(5): start time in clock ticks after boot
        with open("/proc/stat") as f:
            boot = next(int(line.split()[1]) for line in f if line.startswith("btime"))
        return boot + ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError, StopIteration):
        return time.time()


def usage() -> str:
    width = max(map(len, COMMANDS))
    lines = ["usage: warpgym COMMAND [ARGS...]   (warpgym COMMAND --help for its flags)", "", "commands:"]
    lines += [f"  {name:<{width}}  {text}" for name, (_, text) in COMMANDS.items()]
    lines += ["", "  --version   print warpgym's version"]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(usage())
        return 0
    if argv[0] == "--version":
        from importlib.metadata import PackageNotFoundError, version  # noqa: PLC0415

        try:
            print(f"warpgym {version('warpgym')}")
        except PackageNotFoundError:  # a source checkout that was never pip-installed
            from warpgym import __version__  # noqa: PLC0415

            print(f"warpgym {__version__}")
        return 0
    name, rest = argv[0], argv[1:]
    if name not in COMMANDS:
        print(f"warpgym: unknown command {name!r}; choose one of {', '.join(COMMANDS)} (warpgym --help)",
              file=sys.stderr)
        return 2
    sys.argv[0] = f"warpgym {name}"  # argparse names the command in its usage and error lines
    module = importlib.import_module(f"warpgym.cli.{COMMANDS[name][0]}")
    return module.main(rest)
