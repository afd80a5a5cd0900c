"""Every script in scripts/ and benchmarks/ answers a wrong path, a missing extra or an impossible flag with a line
that names it: no traceback, nothing measured first. (train.py's flags: tests/test_reliability.py;
damaged checkpoints: tests/test_damaged_files.py.)"""

import glob
import os
import subprocess
import sys
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
    ("rllib_vs_warpgym.py", ["--report", MISSING], None, f"--report {MISSING}: no comparison.json there"),
    ("rllib_vs_warpgym.py", ["--out", MISSING, "--gpus", "0"], None, "--gpus 0: each is a number of GPUs"),
    ("rllib_vs_warpgym.py", ["--out", MISSING, "--gpus", "1", "--rllib-env-runners", "3"], None,
     "--rllib-env-runners 3: must be 1 or more and divide"),
    ("rllib_vs_warpgym.py", ["--out", MISSING, "--gpus", "1", "2", "--rllib-env-runners", "8"], None,
     "--rllib-env-runners 8 with --gpus 1 2: on several GPUs RLlib takes one env runner per GPU"),
    ("train_with.py", ["rllib", "--gpus", "2", "--env-runners", "4"], None,
     "--env-runners 4 with --gpus 2: on several GPUs each GPU takes one env runner beside its learner"),
    ("rllib_overhead.py", ["--envs", "0"], None, "--envs 0: must be positive"),
    ("rllib_overhead.py", [], "ray", 'RLlib is not installed: pip install "warpgym[rllib]"'),
    ("bench.py", ["--num-envs", "0"], None, "--num-envs 0: must be a positive integer, e.g. --num-envs 4096"),
    ("bench.py", ["--physics", "armature=-1"], None, "--physics: armature=-1"),
    ("learner_bench.py", ["--report", MISSING], None, f"--report {MISSING}: no learners.json there"),
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
    ("rollout_capture.py", ["--report", MISSING], None, f"--report {MISSING}: no such file"),
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


@pytest.fixture(scope="module")
def answers(request, tmp_path_factory) -> dict:
    """The selected cases' processes, as many at once as there are cores: each is mostly an interpreter's start
    (about 2 s of one core), and the cases run one by one took 84 s of the suite's 9.5 minutes."""
    chosen = sorted({item.callspec.params["case"] for item in request.session.items
                     if getattr(item, "originalname", None) == "test_a_bad_input_is_named_in_one_line"})
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 2) as pool:
        done = pool.map(lambda i: answer(CASES[i], tmp_path_factory.mktemp(f"case{i}")), chosen)
        return dict(zip(chosen, done))


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
