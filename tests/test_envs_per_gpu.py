"""benchmarks/speed/envs_per_gpu.py: its mini-batch shaping and how it reads time to target over seeds."""

import sys

import pytest

from benchmarks.speed import envs_per_gpu as epg


def run(n, seed, three=None, eight=None):
    hit = {"3.0": None if three is None else {"time_s": three, "samples": 1}, "8.0": None if eight is None else
           {"time_s": eight, "samples": 1}}
    return {"num_envs": n, "seed": seed, "to_target": hit, "samples_per_s": 1e6 * n / 4096}


def test_time_to_target_is_the_median_of_the_seeds_that_got_there_when_most_did():
    doc = {"task": "Ant", "targets": [3.0, 8.0], "throughput": [], "learning": [
        run(4096, 0, 40.0, 120.0), run(4096, 1, 50.0, None), run(4096, 2, 70.0, 150.0),
        run(8192, 0, 30.0, None), run(8192, 1, 35.0, None), run(8192, 2, 90.0, 100.0)]}
    cells = epg.learning_by_size(doc)
    assert cells[4096][3.0] == {"reached": 3, "median_s": 50.0}
    assert cells[4096][8.0] == {"reached": 2, "median_s": 135.0}  # two of three seeds: the median of those two
    assert cells[8192][8.0] == {"reached": 1, "median_s": None}  # one of three is not a typical run
    table = epg.tables(doc)
    assert "| 8192 | 3 | 35 s (3/3) | not reached (1/3) | 2.00 M |" in table


def test_report_puts_runs_made_alike_in_one_table_and_refuses_others(tmp_path, capsys):
    import json

    def doc(throughput, learning, **changes):
        return {"task": "Ant", "device": "GPU", "targets": [3.0, 8.0], "scale_batch": False,
                "throughput": [{"num_envs": n, "env_steps_per_s": 2e6, "samples_per_s": 1.5e6, "peak_mib": 2048,
                                "batch_size": 32768, "iterations": 60} for n in throughput],
                "learning": learning, **changes}

    def write(name, d):
        path = tmp_path / name
        path.write_text(json.dumps(d))
        return str(path)

    first = write("a.json", doc([4096, 8192], [run(4096, 0, 40.0, None), run(8192, 0, 30.0, 90.0)]))
    second = write("b.json", doc([], [run(4096, 1, 50.0, 100.0), run(8192, 1, 20.0, 70.0)]))
    figure = tmp_path / "fig.png"
    assert epg.main(["--report", first, second, "--figure", str(figure)]) == 0
    out = capsys.readouterr().out
    assert "| 8192 | 2 | 25 s (2/2) | 80 s (2/2) | 2.00 M |" in out  # both files' seeds in one median
    assert "| 4096 | 2 | 45 s (2/2) | not reached (1/2) | 1.00 M |" in out
    assert figure.stat().st_size > 0
    for bad, says in ((write("c.json", doc([], [], device="Other GPU")), "made differently"),
                      (write("d.json", doc([8192], [])), "throughput at 8192"),
                      (write("e.json", doc([], [run(4096, 0, 1.0, 2.0)])), "4096 envs seed 0"),
                      (str(tmp_path / "missing.json"), "no such file")):
        with pytest.raises(SystemExit):
            epg.main(["--report", first, bad])
        assert says in capsys.readouterr().err


@pytest.mark.parametrize(("envs", "scale", "expected"), [(4096, False, 32768), (16384, False, 32768),
                                                          (16384, True, 131072), (2048, True, 16384)])
def test_the_mini_batch_keeps_its_size_unless_scaled_with_the_envs(envs, scale, expected):
    assert epg.batch_size("Ant", envs, scale) == expected


def test_the_train_modes_benchmark_reads_an_overlap_report_ratios_phases_and_time_to_target_per_mode():
    """A JSON that benchmarks/speed/overlap.py kept (one throughput run per mode, no rounds, no ready time) reads in
    train_modes' tables as it read in its own."""
    from benchmarks.speed import train_modes as tm

    def run(mode, seed, three, eight):
        hit = {"3.0": three and {"time_s": three, "samples": 1}, "8.0": eight and {"time_s": eight, "samples": 1}}
        return {"mode": mode, "seed": seed, "to_target": hit, "samples_per_s": 1.2e6}

    doc = {"task": "Ant", "device": "GPU", "num_envs": 4096, "targets": [3.0, 8.0], "env_steps_per_s": 1.6e6,
           "throughput": [{"mode": "sequential", "samples_per_s": 1.2e6,
                           "phase_s": {"iteration_s": 0.05, "phase/collect_s": 0.04, "phase/update_s": 0.01}},
                          {"mode": "overlap", "samples_per_s": 1.44e6, "phase_s": None}],
           "learning": [run("sequential", 0, 40.0, 120.0), run("sequential", 1, 60.0, None),
                        run("sequential", 2, 50.0, None), run("overlap", 0, 30.0, 100.0)]}
    table = tm.tables(doc)
    assert "| sequential | 1 of 1 | - | 1.20 M | 0.75 | - | 1.000 | 50.0 ms | 40.0 ms | 10.0 ms | - |" in table
    assert "| overlap | 1 of 1 | - | 1.44 M | 0.90 | - | 1.200 | - | - | - | - |" in table
    assert "| sequential | 3 | 50 s (3/3) | not reached (1/3) | 1.20 M |" in table
    assert "| overlap | 1 | 30 s (1/1) | 100 s (1/1) | 1.20 M |" in table


FAKE_RUN = r"""
import json, signal, sys, time
stopped = []
signal.signal(signal.SIGTERM, lambda *a: stopped.append(1))
with open(sys.argv[1], "w") as f:
    for i, speed in enumerate(json.loads(sys.argv[2])):
        if stopped:
            sys.exit(0)
        f.write(json.dumps({"iteration": i, "time_s": i, "samples": i, "speed": speed}) + "\n")
        f.flush()
        time.sleep(0.2)
sys.exit(3)  # trained to the end: no stop came
"""


@pytest.mark.parametrize(("speeds", "stops"), [([0.5, 2.0, 3.5, 5.0] + [9.0] * 30, True),
                                               ([0.5, 2.0, 3.5, 5.0, 7.9, 7.0, 6.0], False)])
def test_a_learning_run_ends_once_it_reached_the_last_target_and_not_before(tmp_path, speeds, stops):
    import json
    import subprocess

    proc = subprocess.Popen([sys.executable, "-c", FAKE_RUN, str(tmp_path / "metrics.jsonl"), json.dumps(speeds)])
    stopper = epg.StopAtTargets(proc, str(tmp_path), (3.0, 8.0), interval=0.1)
    code = proc.wait(timeout=60)
    assert stopper.stop() is stops
    assert code == (0 if stops else 3)  # 0: the stop came before the run's 34 rows were written


def test_a_throughput_run_cut_too_short_to_time_gives_no_samples_per_s_and_says_why():
    from types import SimpleNamespace

    args = SimpleNamespace(task="Ant", scale_batch=False, throughput_seconds=30.0)
    run = {"summary": {"iterations": 2, "steady_samples_per_s_median": 5.6e5, "steady_phase_s_median": {}}, "peak_mib": 9}
    row = epg.throughput_row(32768, 2.9e6, run, args)
    assert row["samples_per_s"] is None and "2 iterations in 30 s" in row["too_short"]
    run["summary"]["iterations"] = 60
    assert epg.throughput_row(16384, 2.5e6, run, args)["samples_per_s"] == 5.6e5
    doc = {"task": "Ant", "device": "GPU", "targets": [3.0, 8.0], "throughput": [row], "learning": []}
    assert "| 32768 | 2.90 M | - | - |" in epg.tables(doc)


def test_the_train_modes_benchmark_times_no_mode_from_a_run_too_short_to_time_it():
    """A compiled run's first update compiles for seconds: a short throughput run is all warm-up
    (on an H100, 3 iterations in 40 s read 0.08 M samples/s), and must not enter the table as a rate."""
    import argparse

    from benchmarks.speed import train_modes as tm

    def run(iterations):
        return {"summary": {"iterations": iterations, "steady_samples_per_s_median": 8e4,
                            "steady_phase_s_median": {"iteration_s": 1.6}}, "peak_mib": 100}

    args = argparse.Namespace(throughput_seconds=40.0)
    short = tm.throughput_row("compiled", 0, run(3), args)
    assert short["samples_per_s"] is None and short["phase_s"] is None
    assert "3 iterations in 40 s" in short["too_short"] and "--throughput-seconds" in short["too_short"]
    timed = tm.throughput_row("compiled", 1, run(epg.MIN_ITERATIONS), args)
    assert timed["samples_per_s"] == 8e4 and "too_short" not in timed
    doc = {"task": "Ant", "device": "GPU", "num_envs": 4096, "targets": [3.0, 8.0], "env_steps_per_s": 1e6,
           "throughput": [short], "learning": []}
    assert "| compiled | 0 of 1 | not timed: 3 iterations" in tm.tables(doc)
    doc["throughput"].append(timed)  # a second round timed it: the median is of that round alone
    assert "| compiled | 1 of 2 | - | 0.08 M |" in tm.tables(doc)
