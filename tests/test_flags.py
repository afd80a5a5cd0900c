"""Every flag of every `warpgym` command, given a wrong value, ends the command with exit status 2 and one line
that names the flag, the value and a fix, before anything is built (warpgym/cli/flags.py)."""

import argparse
import math
import os
from dataclasses import fields

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from agents.config import Config
from warpgym.cli import bench, eval as eval_command, play, plot, sim2sim, train_args, train_with
from warpgym.cli.flags import Number

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
POLICY = os.path.join(ROOT, "tests", "data", "ant_armature_policy.pt")

# command: (its parser, how it parses and checks a command line, the positional arguments it needs)
COMMANDS = {
    "train": (train_args.parser, train_args.parse_args, []),
    "train-with": (train_with.parser, train_with.parse_args, ["skrl"]),
    "play": (play.parser, play.parse_args, [POLICY]),
    "eval": (eval_command.parser, eval_command.parse_args, [POLICY]),
    "sim2sim": (sim2sim.parser, sim2sim.main, [POLICY]),
    "bench": (bench.parser, bench.main, []),
    "plot": (plot.parser, plot.main, [ROOT]),
}


def flags_of(make) -> list[argparse.Action]:
    return [a for a in make()._actions if a.option_strings and not isinstance(a, argparse._HelpAction)]


def refused(parse, argv, capsys) -> str:
    """The one line a command answered ``argv`` with, after checking it exited with status 2."""
    with pytest.raises(SystemExit) as done:
        parse(argv)
    err = capsys.readouterr().err
    assert done.value.code == 2, (argv, done.value.code, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, (argv, err)
    return lines[0]


def test_every_number_flag_declares_its_range():
    """A flag that takes a number takes a ``Number``: its wrong values are then the ones walked below."""
    plain = [(name, a.option_strings[0]) for name, (make, _, _) in COMMANDS.items() for a in flags_of(make)
             if a.type in (int, float)]
    assert plain == []


def wrong_numbers(number: Number):
    """Texts that are not a number of the kind, or lie outside its range, or are not finite."""
    junk = st.text(alphabet="abcxyz,.;e+", min_size=1, max_size=6).filter(lambda t: not _parses(number, t))
    below = st.floats(max_value=number.low, allow_nan=False, allow_infinity=False, width=32)
    if number.kind is int:
        below = st.integers(max_value=int(number.low) - (0 if number.strict else 1), min_value=-10**9)
    else:
        below = below.filter(lambda v: not number.holds(v))
    return st.one_of(junk, below.map(str), st.sampled_from(["nan", "inf", "-inf"] if number.kind is float else ["1.5"]))


def _parses(number: Number, text: str) -> bool:
    try:
        number.kind(text)
        return True
    except ValueError:
        return False


NUMBER_FLAGS = [(name, a.option_strings[0], a.type) for name, (make, _, _) in COMMANDS.items()
                for a in flags_of(make) if isinstance(a.type, Number)]


@pytest.mark.parametrize(("command", "flag", "number"), NUMBER_FLAGS, ids=[f"{c} {f}" for c, f, _ in NUMBER_FLAGS])
@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(data=st.data())
def test_a_wrong_number_is_named_with_its_flag_and_a_value_that_works(command, flag, number, data, capsys):
    value = data.draw(wrong_numbers(number))
    _, parse, positional = COMMANDS[command]
    line = refused(parse, [*positional, f"{flag}={value}"], capsys)
    assert f"{flag} {value}: must be" in line and f"e.g. {flag} {number.example}" in line, line
    assert number.holds(number.kind(number.example))  # the example given is a value that works


CHOICE_FLAGS = [(name, a.option_strings[0], a.choices) for name, (make, _, _) in COMMANDS.items()
                for a in flags_of(make) if a.choices]


@pytest.mark.parametrize(("command", "flag", "choices"), CHOICE_FLAGS, ids=[f"{c} {f}" for c, f, _ in CHOICE_FLAGS])
def test_a_wrong_choice_names_the_flag_and_the_choices(command, flag, choices, capsys):
    _, parse, positional = COMMANDS[command]
    line = refused(parse, [*positional, f"{flag}=nonsense"], capsys)
    assert f"{flag}: invalid choice: 'nonsense'" in line and str(next(iter(choices))) in line, line


CONFIGURABLE = [f for f in fields(Config) if f.name not in train_args.NOT_CONFIGURABLE]


def wrong_setting(field) -> str:
    """A value of the wrong kind or range for a Config field, as `--config NAME=VALUE` would carry it."""
    default = getattr(Config, field.name, None)
    if isinstance(default, bool):
        return "maybe"
    if isinstance(default, (int, float)):
        return "-1"
    if isinstance(default, tuple):
        return "x,y" if field.name == "net_dims" else "-1"
    return "nonsense"  # activation, multi_gpu, target


@pytest.mark.parametrize("field", CONFIGURABLE, ids=[f.name for f in CONFIGURABLE])
def test_a_wrong_config_value_is_refused_before_anything_is_built(field, capsys):
    value = wrong_setting(field)
    line = refused(train_args.parse_args, ["--config", f"{field.name}={value}"], capsys)
    assert line.startswith("warpgym train: error: --config: ") and field.name in line and value.split(",")[0] in line


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(name=st.sampled_from([f.name for f in CONFIGURABLE if isinstance(getattr(Config, f.name, None), float)
                             and not isinstance(getattr(Config, f.name), bool)]),
       value=st.one_of(st.floats(max_value=-1e-6), st.just(math.nan), st.text(alphabet="abc", min_size=1, max_size=4)))
def test_a_float_setting_out_of_range_or_not_a_number_is_refused(name, value, capsys):
    refused(train_args.parse_args, ["--config", f"{name}={value}"], capsys)


@pytest.mark.parametrize(("command", "argv", "says"), [
    ("train", ["--device", "cuda:7"], "--device cuda:7: device 'cuda:7' is not on this machine"),
    ("train", ["--device", "tpu"], "--device tpu: device 'tpu' is not a device name"),
    ("play", [POLICY, "--device", "cuda:7"], "--device cuda:7"),
    ("eval", ["/nowhere/at/all"], "no checkpoint at /nowhere/at/all"),
    ("sim2sim", ["/nowhere/at/all"], "no checkpoint at /nowhere/at/all"),
    ("plot", ["/nowhere/at/all"], "no metrics.jsonl in /nowhere/at/all"),
    ("bench", ["--tasks", "Hopper-v9"], "--tasks: "),
    ("train-with", ["nolearner"], "learner 'nolearner': choose one of"),
    ("train-with", ["skrl", "--task", "Go1VelocityRough-v0"],
     "only rsl_rl trains the legged tasks (its observation groups give the critic its own observation)"),
])
def test_a_wrong_path_device_or_name_is_one_line(command, argv, says, capsys, monkeypatch):
    import torch

    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)  # as on a machine without a GPU
    line = refused(COMMANDS[command][1], argv, capsys)
    assert says in line, line
