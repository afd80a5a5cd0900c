"""The commands' flags: a parser whose every error is one line, and typed numbers whose errors name the
flag, the value and one that works.

    warpgym train: error: --num-envs -4: must be a positive integer, e.g. --num-envs 4096

Exit status 2, argparse's own for a usage error, and nothing built or run before it. A numeric flag takes a
``Number`` as its type (tests/test_flags.py walks every command's flags with wrong values and fails on a number
flag that has none).
"""

from __future__ import annotations

import argparse
import math
import re


class CommandParser(argparse.ArgumentParser):
    def __init__(self, *args, **kwargs):
        kwargs.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str):
        """One line on stderr and exit status 2. argparse writes a flag's error as "argument --flag: ..."; a
        ``Number``'s message already names its flag (``{flag}``), others get it in front."""
        found = re.match(r"argument (\S+?)(?:/\S+)?: (.*)$", message, re.S)
        if found:
            flag, rest = found.groups()
            message = rest.replace("{flag}", flag) if "{flag}" in rest else f"{flag}: {rest}"
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())}\n")


class Number:
    """An argparse type: a ``kind`` (int or float) of at least ``low`` (above it where ``strict``), finite."""

    def __init__(self, kind: type, low: float, strict: bool, example):
        self.kind, self.low, self.strict, self.example = kind, low, strict, example
        self.__name__ = kind.__name__  # argparse names a type by it in its own messages

    def describe(self) -> str:
        noun = "integer" if self.kind is int else "number"
        if self.low == 0:
            return f"a positive {noun}" if self.strict else f"0 or a positive {noun}"
        return f"{'an' if noun == 'integer' else 'a'} {noun} {'above' if self.strict else 'of at least'} {self.low:g}"

    def holds(self, value) -> bool:
        return math.isfinite(value) and (value > self.low if self.strict else value >= self.low)

    def __call__(self, text: str):
        try:
            value = self.kind(text)
        except ValueError:
            value = None
        if value is None or not self.holds(value):
            raise argparse.ArgumentTypeError(f"{{flag}} {text}: must be {self.describe()}, e.g. {{flag}} {self.example}")
        return value


def positive_int(example: int) -> Number:
    return Number(int, 0, True, example)


def non_negative_int(example: int) -> Number:
    return Number(int, 0, False, example)


def positive_float(example: float) -> Number:
    return Number(float, 0, True, example)


def non_negative_float(example: float) -> Number:
    return Number(float, 0, False, example)


def check_device(ap: argparse.ArgumentParser, device: str | None, flag: str = "--device") -> None:
    """A device this machine has, checked before anything is built (``None``: the default, which always is)."""
    if device is None:
        return
    from warpgym.sim.device import resolve_device  # noqa: PLC0415

    try:
        resolve_device(device)
    except ValueError as e:
        ap.error(f"{flag} {device}: {e}".replace("pass device='cpu'", f"pass {flag} cpu"))


def check_checkpoint(ap: argparse.ArgumentParser, path: str) -> None:
    """A checkpoint file, or a run directory that holds checkpoint.pt (whether it loads is the command's to say)."""
    import os  # noqa: PLC0415

    file = os.path.join(path, "checkpoint.pt") if os.path.isdir(path) else path
    if not os.path.isfile(file):
        ap.error(f"no checkpoint at {file}: pass a run directory written by warpgym train, or a checkpoint file")
