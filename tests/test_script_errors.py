"""Every script in scripts/ and benchmarks/ answers a wrong path, a missing extra or an impossible flag with a line
that names it: no traceback, nothing measured first. (train.py's flags: tests/test_reliability.py;
damaged checkpoints: tests/test_damaged_files.py.)"""

import contextlib
import glob
import io
import os
import runpy
import subprocess
import sys
import traceback
import warnings
from concurrent.futures import ThreadPoolExecutor

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
POLICY = os.path.join(ROOT, "tests", "data", "ant_armature_policy.pt")
MISSING = "/nowhere/at/all"

CASES = [
    ("plot.py", [MISSING], None, f"no metrics.jsonl in {MISSING}"),
    ("play.py", [MISSING, "--device", "cpu"], None, f"no checkpoint at {MISSING}"),
    ("play.py", [POLICY, "--steps", "0"], None, "--steps 0: must be a positive integer, e.g. --steps 300"),
    ("play.py", [POLICY, "--device", "cpu", "--video", "a.mp4"], "av", "--video: clips need the video extra (av is missing)"),
    ("play.py", [POLICY, "--device", "cpu", "--gif", "a.gif"], "PIL", "--gif: clips need the video extra (PIL is missing)"),
    ("sim2sim.py", [MISSING, "--device", "cpu"], None, f"no checkpoint at {MISSING}"),
    ("sim2sim.py", [POLICY, "--finer", "0"], None, "--finer 0: must be a positive integer, e.g. --finer 4"),
    ("train_with.py", ["nolearner"], None, "learner 'nolearner': choose one of"),
    ("train_with.py", ["skrl", "--device", "cpu"], "skrl", 'skrl is not installed: pip install "warpgym[skrl]"'),
    ("train_with.py", ["rllib", "--device", "cpu"], "ray", 'rllib is not installed: pip install "warpgym[rllib]"'),
    ("train_with.py", ["skrl", "--batch-size", "4"], None, "--batch-size is an rllib setting"),
    ("train_with.py", ["skrl", "--env-runners", "2"], None, "--env-runners is an rllib setting"),
    ("train_with.py", ["rllib", "--env-runners=-1"], None, "--env-runners -1: must be 0 or a positive integer"),
    ("learners.py", ["--report", MISSING], None, f"--report {MISSING}: no comparison.json there"),
    ("learners.py", ["--out", MISSING, "--gpus", "0"], None, "--gpus 0: each is a number of GPUs"),
    ("learners.py", ["--out", MISSING, "--gpus", "1", "--rllib-env-runners", "3"], None,
     "--rllib-env-runners 3: must be 1 or more and divide"),
    ("learners.py", ["--out", MISSING, "--gpus", "1", "2", "--rllib-env-runners", "8"], None,
     "--rllib-env-runners 8 with --gpus 1 2: on several GPUs RLlib takes one env runner per GPU"),
    ("train_with.py", ["rllib", "--gpus", "2", "--env-runners", "4"], None,
     "--env-runners 4 with --gpus 2: on several GPUs each GPU takes one env runner beside its learner"),
    ("rllib_overhead.py", ["--envs", "0"], None, "--envs 0: must be positive"),
    ("rllib_overhead.py", [], "ray", 'RLlib is not installed: pip install "warpgym[rllib]"'),
    ("bench.py", ["--num-envs", "0"], None, "--num-envs 0: must be a positive integer, e.g. --num-envs 4096"),
    ("bench.py", ["--physics", "armature=-1"], None, "--physics: armature=-1"),
    ("learners.py", ["--out", MISSING, "--gpus", "2", "--learners", "skrl"], None,
     "--learners skrl with --gpus 2: these adapters train on one GPU"),
    ("robot_steps.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("robot_steps.py", ["--report", os.path.join(ROOT, "docs", "bench", "cpu_exits.json")], None,
     "no robots' rows in it; it is not a `warpgym bench --robots` JSON"),
    ("video_cost.py", ["--out", MISSING, "--seconds", "-1"], None, "--seconds -1.0 and --eval-gap 20.0: both must be positive"),
    ("cold_start.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("seed_spread.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("reliability_soak.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("reliability_soak.py", ["bogus"], None, "invalid choice: 'bogus'"),
    ("scaling.py", ["--out", MISSING, "--gpus", "0"], None, "--gpus 0: each is a number of GPUs, 1 or more"),
    ("scaling.py", ["--report", MISSING], None, f"--report {MISSING}: no scaling_<task>.json there"),
    ("fidelity.py", ["--out", MISSING, "--replay", MISSING], None, f"--replay {MISSING}: not a finished run directory"),
    ("fidelity.py", ["--out", MISSING, "--probes", MISSING], None, f"--probes {MISSING}: no such checkpoint file"),
    ("fidelity.py", ["--report", MISSING], None, f"--report {MISSING}: no fidelity.json"),
    ("exits.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("nodes.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("nodes.py", ["--out", MISSING, "--gpus", "3", "--nodes", "2"], None, "--gpus 3 --nodes 2: need at least 2 nodes"),
    ("reacher_planner.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("reacher_planner.py", ["--out", MISSING, "--knots", "1"], None, "--knots 1: need"),
    ("conformance.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("train_modes.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("train_modes.py", ["--out", MISSING, "--task", "Nope-v9"], None, "--task Nope-v9"),
    ("suite_versions.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
    ("exits.py", ["--out", MISSING, "--gpus", "0"], None, "--gpus 0"),
    ("envs_per_gpu.py", ["--out", MISSING, "--envs", "1000"], None,
     "1000 envs: a rollout of 16000 samples (x horizon_len 16) does not split into mini-batches of 32768"),
    ("envs_per_gpu.py", ["--out", MISSING, "--target-envs", "0"], None, "--target-envs 0: envs per GPU must be positive"),
    ("envs_per_gpu.py", ["--out", MISSING, "--throughput-iterations", "5"], None,
     "--throughput-iterations 5: a throughput run needs at least 20 iterations"),
]


def command_of(name: str) -> list[str]:
    """How a script is started: scripts/ by path, a benchmark as a module of the benchmarks package."""
    script = glob.glob(os.path.join(ROOT, "scripts", name))
    bench = glob.glob(os.path.join(ROOT, "benchmarks", "**", name), recursive=True)
    assert len(script + bench) == 1, script + bench
    if script:
        return [sys.executable, script[0]]
    return [sys.executable, "-m", os.path.relpath(bench[0], ROOT)[:-3].replace(os.sep, ".")]


def answer(case: tuple, folder) -> subprocess.CompletedProcess:
    """One case's process, run in ``folder``; a missing extra is a package there that fails to import."""
    name, args, missing, _ = case
    env = dict(os.environ)
    if missing:  # a package that fails to import, as if its extra were not installed
        (folder / missing).mkdir()
        (folder / missing / "__init__.py").write_text(f"raise ImportError('No module named {missing}', name='{missing}')\n")
        env["PYTHONPATH"] = os.pathsep.join([str(folder), env.get("PYTHONPATH", "")])
    command = command_of(name)
    if command[1] == "-m":  # from the checkout
        env["PYTHONPATH"] = os.pathsep.join([env.get("PYTHONPATH", ""), ROOT])
    return subprocess.run([*command, *args], cwd=folder, env=env, capture_output=True, text=True, timeout=120)


def answer_here(case: tuple, folder) -> subprocess.CompletedProcess:
    """One case run as ``python SCRIPT ARGS`` / ``python -m MODULE ARGS`` runs it, in this process (its imports are
    done): the exit status and stderr a process would give, and an escaping exception's traceback as stderr."""
    name, args, _, _ = case
    command = command_of(name)
    saved = sys.argv, list(sys.path), os.getcwd()
    err, code = io.StringIO(), 0
    os.chdir(folder)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # runpy: the module was imported by another test
            sys.argv = [command[-1], *args]
            if command[1] == "-m":
                runpy.run_module(command[2], run_name="__main__", alter_sys=True)
            else:
                runpy.run_path(command[1], run_name="__main__")
    except SystemExit as stop:
        code = stop.code if isinstance(stop.code, int) else (0 if stop.code is None else 1)
        if not isinstance(stop.code, (int, type(None))):
            err.write(f"{stop.code}\n")  # sys.exit("message") prints it
    except BaseException:  # noqa: BLE001  (a process would have died with this traceback)
        code = 1
        err.write(traceback.format_exc())
    finally:
        sys.argv, sys.path[:] = saved[0], saved[1]
        os.chdir(saved[2])
    return subprocess.CompletedProcess([*command, *args], code, "", err.getvalue())


@pytest.fixture(scope="module")
def answers(request, tmp_path_factory) -> dict:
    """The selected cases' answers. A case with a missing extra runs as a process of its own, with a package on its
    path that fails to import; the others run in this process, whose imports are done (each process's start, about
    2-4 s of a core of torch's and Warp's imports, made 45 processes 73 s of the suite on two cores), while the
    processes run beside."""
    chosen = sorted({item.callspec.params["case"] for item in request.session.items
                     if getattr(item, "originalname", None) == "test_a_bad_input_is_named_in_one_line"})
    alone = [i for i in chosen if CASES[i][2]]
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        started = pool.map(lambda i: answer(CASES[i], tmp_path_factory.mktemp(f"case{i}")), alone)
        here = {i: answer_here(CASES[i], tmp_path_factory.mktemp(f"case{i}")) for i in chosen if i not in alone}
        return {**here, **dict(zip(alone, started))}


@pytest.mark.parametrize("case", range(len(CASES)),
                         ids=[f"{c[0]} {' '.join(c[1])}" + (f" without {c[2]}" if c[2] else "") for c in CASES])
def test_a_bad_input_is_named_in_one_line(answers, case):
    says = CASES[case][3]
    done = answers[case]
    assert done.returncode != 0 and "Traceback" not in done.stderr, done.stderr[-2000:]
    assert says in done.stderr, done.stderr[-2000:]


def test_a_damaged_report_is_named_in_one_line(tmp_path):
    from benchmarks.harness import read_report

    bad = tmp_path / "half.json"
    bad.write_text('{"rows": [')
    with pytest.raises(SystemExit, match=f"--report {bad}: cannot be read as JSON .*; pass the exits.json"):
        read_report(str(bad), "the exits.json a run of this script wrote")
    bad.write_text('{"rows": []}')
    assert read_report(str(bad), "x") == {"rows": []}
