"""The ``warpgym`` command: subcommands, --version, one-line errors, and a wheel that carries it.
(CI also installs the wheel into a fresh environment and trains from another directory: .ci/run.)"""

import os
import subprocess
import sys
import tomllib
import zipfile

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PYPROJECT = tomllib.load(open(os.path.join(ROOT, "pyproject.toml"), "rb"))


def start(*args, cwd=ROOT) -> subprocess.Popen:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([ROOT, os.environ.get("PYTHONPATH", "")]))
    return subprocess.Popen([sys.executable, "-m", "warpgym", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, cwd=cwd, env=env)


def finish(proc: subprocess.Popen) -> subprocess.CompletedProcess:
    out, err = proc.communicate(timeout=120)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)


def warpgym(*args, cwd=ROOT):
    return finish(start(*args, cwd=cwd))


def test_version_is_the_projects():
    done = warpgym("--version")
    assert done.returncode == 0 and done.stdout.strip() == f"warpgym {PYPROJECT['project']['version']}"


def test_every_subcommand_answers_help_under_its_own_name():
    from warpgym.cli import COMMANDS

    assert set(COMMANDS) == {"train", "play", "plot", "sim2sim", "train-with", "bench", "eval", "export"}
    for pair in (list(COMMANDS)[i:i + 2] for i in range(0, len(COMMANDS), 2)):  # two at a time: two cores
        for name, proc in [(name, start(name, "--help")) for name in pair]:
            done = finish(proc)
            assert done.returncode == 0 and f"usage: warpgym {name}" in done.stdout, (name, done.stderr[-500:])


@pytest.mark.parametrize(("args", "code", "says"), [
    (["nonsense"], 2, "unknown command 'nonsense'; choose one of train, play"),
    (["play", "/nowhere/at/all", "--device", "cpu"], 2, "no checkpoint at /nowhere/at/all"),
    (["train", "--num-envs", "0"], 2, "--num-envs"),
])
def test_a_wrong_command_or_path_gets_one_line(args, code, says, tmp_path):
    done = warpgym(*args, cwd=tmp_path)
    assert done.returncode == code and "Traceback" not in done.stderr, done.stderr[-2000:]
    assert says in done.stderr, done.stderr[-2000:]


def test_the_wheel_carries_the_command_and_all_three_packages(tmp_path):
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                    str(tmp_path), ROOT], check=True, capture_output=True, timeout=300)
    (wheel,) = tmp_path.glob("warpgym-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    for module in ("warpgym/cli/train.py", "warpgym/__main__.py", "warpgym/sim/simulator.py",
                   "warpgym/compile/preload.py", "warpgym/media/render.py", "kernels/robots/observations.py",
                   "agents/runner.py"):
        assert module in names, module
    assert not [n for n in names if n.startswith(("tests/", "benchmarks/", "scripts/"))]
    entry_points = next(n for n in names if n.endswith("entry_points.txt"))
    assert "warpgym = warpgym.cli:main" in zipfile.ZipFile(wheel).read(entry_points).decode()


def test_the_training_clock_starts_with_the_process():
    """train's wall-clock axis starts at the process's start (from /proc), before any import."""
    psutil = pytest.importorskip("psutil")
    from warpgym.cli import process_start_time

    assert process_start_time() == pytest.approx(psutil.Process().create_time(), abs=0.05)


def test_bench_times_tasks_of_every_family_in_one_table_from_their_entries(capsys, tmp_path):
    """``warpgym bench --tasks``: each family's row comes from its registry entry's ``bench`` (the suite's, the
    legged tasks' and the robots' own timings), the table one row per task and size, the rates positive; the tasks
    of ``--legged`` (its older name) join those of ``--tasks``."""
    import json
    import statistics

    from warpgym.cli import bench
    from warpgym.tasks.registry import REGISTRY

    assert all(callable(e.bench) for e in REGISTRY.values())
    names = ["Swimmer-v5", "Ant", "Go1VelocityFlat-v0"]
    out = tmp_path / "bench.json"
    assert bench.main(["--tasks", *names[:2], "--legged", names[2], "--num-envs", "2", "--steps", "2", "--repeats", "1", "--warmup", "1",
                       "--device", "cpu", "--out", str(out)]) == 0
    table = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ") and "---" not in line]
    assert [row.split(" | ")[0].strip("| ") for row in table[1:]] == names
    rows = json.loads(out.read_text())["rows"]
    assert [r["task"] for r in rows] == names
    for r in rows:
        for key in ("env_steps_per_s", "mjwarp_steps_per_s"):
            value = r[key]
            assert (statistics.median(value) if isinstance(value, list) else value) > 0, r
