"""docs/cli.md, the reference of every ``warpgym`` command's flags, written from the commands' own parsers, so the
page cannot say what ``--help`` does not (tests/test_docs.py regenerates it and compares).

    python -m warpgym.cli.reference docs/cli.md        # write it
    python -m warpgym.cli.reference --check docs/cli.md   # exit 1 if it differs from the parsers
"""

from __future__ import annotations

import argparse
import importlib
import sys

from warpgym.cli import COMMANDS

HEADER = """# Command-line reference

Written by `python -m warpgym.cli.reference docs/cli.md` from the parsers themselves; `warpgym COMMAND --help`
prints the same flags with the longer descriptions. `scripts/COMMAND.py` in a source checkout takes the same flags.
"""


def command_parser(name: str) -> argparse.ArgumentParser:
    """The parser of ``warpgym name``, as its ``main`` builds it."""
    module_name = COMMANDS[name][0]
    if module_name == "train":  # the training flags are shared with warpgym train-with's learners
        module_name = "train_args"
    parser = importlib.import_module(f"warpgym.cli.{module_name}").parser()
    parser.prog = f"warpgym {name}"
    return parser


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def _default(action: argparse.Action) -> str:
    if action.default in (None, argparse.SUPPRESS) or isinstance(action, (argparse._StoreTrueAction,
                                                                           argparse._StoreFalseAction)):
        return ""
    value = action.default
    if isinstance(value, (list, tuple)):
        value = " ".join(str(v) for v in value)
    return f"`{value}`" if str(value) != "" else ""


def _flag(action: argparse.Action, formatter) -> str:
    if not action.option_strings:
        return f"`{action.metavar or action.dest}`"
    metavar = "" if action.nargs == 0 else " " + formatter._format_args(action, action.dest.upper())
    return ", ".join(f"`{s}{metavar}`" for s in action.option_strings)


def section(name: str) -> str:
    parser = command_parser(name)
    formatter = parser._get_formatter()
    usage = " ".join(parser.format_usage().split())
    if usage.startswith("usage: "):
        usage = usage[len("usage: "):]
    lines = [f"## warpgym {name}", "", COMMANDS[name][1][0].upper() + COMMANDS[name][1][1:] + ".", "",
             f"    {usage}", "", "| flag | default | what |", "|---|---|---|"]
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction) or action.help == argparse.SUPPRESS:
            continue
        what = formatter._expand_help(action) if action.help else ""
        if action.choices is not None and "{" not in _flag(action, formatter):
            what = f"{what} (one of {', '.join(map(str, action.choices))})".strip()
        lines.append(f"| {_flag(action, formatter)} | {_default(action)} | {_cell(what)} |")
    return "\n".join(lines)


def render() -> str:
    return HEADER + "\n" + "\n\n".join(section(name) for name in COMMANDS) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m warpgym.cli.reference", description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="the page to write (docs/cli.md)")
    ap.add_argument("--check", action="store_true", help="compare instead of writing; exit 1 on a difference")
    args = ap.parse_args(argv)
    text = render()
    if args.check:
        with open(args.out) as f:
            same = f.read() == text
        print(f"{args.out}: {'up to date' if same else 'differs from the parsers; regenerate it'}")
        return 0 if same else 1
    with open(args.out, "w") as f:
        f.write(text)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
