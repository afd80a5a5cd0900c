"""The side-by-side benchmark's report: mjlab's target read from its own TensorBoard log at the mark, warpgym's
time to it over smoothed rows, and the goals' verdicts (no mjlab, no GPU: the logs are written here)."""

import json

import pytest

from benchmarks.learning import mjlab_side_by_side as sbs

STARTED = 1_000_000.0


def write_mjlab(folder, rows, levels=None):
    """mjlab's TensorBoard tags; ``levels(t)``: its curriculum's mean terrain level (rough ground)."""
    from torch.utils.tensorboard import SummaryWriter

    writer = SummaryWriter(str(folder / "go1_velocity" / "run"))
    for it, (t, ret, err) in enumerate(rows):
        writer.add_scalar("Train/mean_reward", ret, it, walltime=STARTED + t)
        writer.add_scalar("Metrics/twist/error_vel_xy", err, it, walltime=STARTED + t)
        writer.add_scalar("Perf/total_fps", 100_000.0, it, walltime=STARTED + t)
        if levels:
            writer.add_scalar("Curriculum/terrain_levels/mean", levels(t), it, walltime=STARTED + t)
    writer.close()


def write_ours(folder, rows, levels=None):
    folder.mkdir(parents=True)
    with open(folder / "metrics.jsonl", "w") as f:
        for it, (t, ret) in enumerate(rows):
            row = {"iteration": it, "time_s": t, "return": ret, "samples_per_s": 300_000.0, "episode/error_vel_xy": 0.5}
            f.write(json.dumps(row | ({"curriculum/terrain_level": levels(t)} if levels else {})) + "\n")


@pytest.fixture
def out(tmp_path):
    task = "Go1VelocityFlat-v0"
    (tmp_path / "jobs.json").write_text(json.dumps({
        "jobs": [{"task": task, "framework": "mjlab", "started": STARTED}], "device": "GPU", "date": "2026-11-28",
        "num_envs": 4096}))
    # mjlab: return = t / 10 every 10 s up to 500 s
    write_mjlab(tmp_path / f"mjlab-{task}", [(t, t / 10.0, 1.0) for t in range(10, 510, 10)])
    # warpgym seed 0: return = t / 5, so it passes mjlab's 445-s return (43.0) at about 215 s
    write_ours(tmp_path / f"warpgym-{task}-seed0", [(float(t), t / 5.0) for t in range(5, 300, 5)])
    # seed 1 never gets there
    write_ours(tmp_path / f"warpgym-{task}-seed1", [(float(t), 10.0) for t in range(5, 300, 5)])
    return tmp_path


def test_the_target_is_mjlabs_mean_return_in_the_window_before_the_mark(out):
    summary = sbs.summarize(str(out), mark=445.0)
    mj = summary["tasks"]["Go1VelocityFlat-v0"]["mjlab"]
    # rows at 420, 430, 440 s lie in [415, 445]: returns 42, 43, 44
    assert mj["at_mark"]["return"] == pytest.approx(43.0)
    assert mj["at_mark"]["rows"] == 3
    assert summary["mark_s"] == 445.0


def test_warpgyms_time_is_its_first_smoothed_row_at_the_target_and_a_seed_short_of_it_is_not_reached(out):
    runs = sbs.summarize(str(out), mark=445.0)["tasks"]["Go1VelocityFlat-v0"]["warpgym"]
    # the mean of the rows at t - 10, t - 5 and t is (t - 5) / 5 >= 43 first at t = 220
    assert runs[0]["reached"]["time_s"] == pytest.approx(220.0)
    assert runs[1]["reached"] is None
    table = sbs.table(sbs.summarize(str(out), mark=445.0))
    # a quarter of 445 s is 111 s: 220 s is not met, and the table says which mark it judged
    assert "220 (0.49x) not met" in table
    assert "| 445 (the mark) |" in table and "not reached" in table


def test_without_a_mark_the_15_minute_mark_is_the_target_and_a_run_that_ended_before_it_has_none(out):
    summary = sbs.summarize(str(out))
    assert summary["tasks"]["Go1VelocityFlat-v0"]["mjlab"]["at_mark"]["return"] is None
    assert all(r["reached"] is None for r in summary["tasks"]["Go1VelocityFlat-v0"]["warpgym"])


@pytest.mark.parametrize("name, rows_expected", [
    ("side_by_side_2026-11-28.json", 2 + 2 + 2 * 4),  # two headers, two speed rows, per task mjlab's row and 3 seeds
    ("side_by_side_go1_15min_2026-11-28.json", 2 + 1 + 4),  # the Go1's 15-minute run: one speed row, mjlab, 3 seeds
    ("side_by_side_g1_15min_2026-11-29.json", 2 + 1 + 2),  # the G1's on one GPU: one speed row, mjlab, seed 0
    ("side_by_side_go1_rough_9min_2026-11-29.json", 2 + 1 + 2),  # the Go1 on rough ground, mjlab's first 9 minutes
    ("side_by_side_g1_rough_15min_2026-11-29.json", 2 + 1 + 2),  # the G1 on rough ground, mjlab's 15 minutes
    ("side_by_side_g1_rough_15min_seed1_2026-11-29.json", 2 + 1 + 2),  # again, both frameworks' seed 1, 2-GPU host
])
def test_the_published_tables_are_what_the_report_prints_from_the_committed_summary(name, rows_expected):
    """The legged tables of docs/benchmarks.md (and, for the runs it no longer shows, of the log, docs/history.md),
    row for row, as ``--report`` prints them from the summaries it wrote."""
    import os

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    with open(os.path.join(root, "docs", "bench", "legged", name)) as f:
        summary = json.load(f)
    page = set()
    for doc in ("benchmarks.md", "history.md"):
        with open(os.path.join(root, "docs", doc)) as f:
            page |= set(f.read().splitlines())
    rows = [line for line in sbs.table(summary).splitlines() if line.startswith("| ")]
    assert len(rows) == rows_expected
    assert [r for r in rows if r not in page] == []


def test_several_runs_make_one_table_each_row_dated_and_judged_at_its_own_runs_mark(out, tmp_path, capsys):
    import copy

    early = sbs.summarize(str(out), mark=445.0)
    late = copy.deepcopy(early) | {"date": "2026-12-01", "mark_s": 1000.0}
    rows = [line for line in sbs.table(early, late).splitlines() if line.startswith("| Go1")]
    assert len(rows) == 2 * (1 + 2)  # per run (no bare steps timed here): mjlab's row and two seeds'
    # seed 0's 220 s is 0.49x of the first run's 445-s mark (not met) and 0.22x of the second's 1000 s (met)
    seed0 = [r for r in rows if "warpgym seed 0" in r]
    assert "| 2026-11-28 |" in seed0[0] and "220 (0.49x) not met" in seed0[0]
    assert "| 2026-12-01 |" in seed0[1] and "220 (0.22x) met" in seed0[1]
    assert "| 1000 (the mark) |" in [r for r in rows if "mjlab" in r][1]
    paths = [tmp_path / "a.json", tmp_path / "b.json"]
    for path, summary in zip(paths, (early, late)):
        path.write_text(json.dumps(summary))
    assert sbs.main(["--report", *map(str, paths)]) == 0
    assert capsys.readouterr().out.strip() == sbs.table(early, late)
    with pytest.raises(SystemExit):  # one figure is one run's
        sbs.main(["--report", *map(str, paths), "--figure", str(tmp_path / "f.png")])
    assert "give one --report (got 2)" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        sbs.main(["--report", str(tmp_path / "missing")])
    assert "neither a run folder nor a summary.json" in capsys.readouterr().err


def test_mjlabs_row_names_the_seed_its_run_was_started_with(out):
    # a run started before jobs.json kept the seed used mjlab's default
    assert "| mjlab seed 42 |" in sbs.table(sbs.summarize(str(out)))
    jobs = json.loads((out / "jobs.json").read_text())
    (out / "jobs.json").write_text(json.dumps(jobs | {"mjlab_seed": 7}))
    summary = sbs.summarize(str(out))
    assert summary["mjlab_seed"] == 7
    assert "| mjlab seed 7 |" in sbs.table(summary) and "seed 42" not in sbs.table(summary)


def test_the_curves_are_thinned_to_one_point_per_interval_and_drawn(out, tmp_path):
    summary = sbs.summarize(str(out))
    mj = summary["tasks"]["Go1VelocityFlat-v0"]["mjlab"]["curve"]
    # mjlab's rows every 10 s are all kept (CURVE_EVERY is 5 s); warpgym's every 5 s too, each [time, return]
    assert [t for t, _ in mj] == [float(t) for t in range(10, 510, 10)]
    ours = summary["tasks"]["Go1VelocityFlat-v0"]["warpgym"][0]["curve"]
    assert ours[1] == [10.0, 2.0]
    assert sbs.curve([{"time_s": t / 10, "return": 1.0} for t in range(100)], every=5.0) == [[0.0, 1.0], [5.0, 1.0]]
    png = tmp_path / "fig.png"
    sbs.draw(summary, str(png))
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_on_rough_ground_both_logs_terrain_levels_reach_the_table_and_a_second_row_of_panels(tmp_path):
    from PIL import Image

    task = "Go1VelocityRough-v0"
    (tmp_path / "jobs.json").write_text(json.dumps({
        "jobs": [{"task": task, "framework": "mjlab", "started": STARTED}], "device": "GPU", "date": "2026-11-30",
        "num_envs": 4096}))
    write_mjlab(tmp_path / f"mjlab-{task}", [(t, t / 10.0, 1.0) for t in range(10, 510, 10)],
                levels=lambda t: t / 100.0)
    write_ours(tmp_path / f"warpgym-{task}-seed0", [(float(t), t / 5.0) for t in range(5, 300, 5)],
               levels=lambda t: t / 50.0)
    summary = sbs.summarize(str(tmp_path), mark=445.0)
    e = summary["tasks"][task]
    # mjlab's levels at 420, 430, 440 s: 4.3 on average; warpgym's at 210, 215, 220 s (where it reached 43): 4.3
    assert e["mjlab"]["at_mark"]["terrain_level"] == pytest.approx(4.3)
    assert e["warpgym"][0]["reached"]["terrain_level"] == pytest.approx(4.3)
    assert e["mjlab"]["levels"][0] == [10.0, 0.1] and e["warpgym"][0]["levels"][1] == [10.0, 0.2]
    table = sbs.table(summary)
    assert "| 43.00 (level 4.30) |" in table and "220 (0.49x) (level 4.30) not met" in table
    flat, rough = tmp_path / "flat.png", tmp_path / "rough.png"
    sbs.draw(summary, str(rough))
    for run in [e["mjlab"], *e["warpgym"]]:
        run.pop("levels")
    sbs.draw(summary, str(flat))
    # the curriculum's row doubles the figure's height; without levels there is none
    assert Image.open(rough).height == 2 * Image.open(flat).height


def test_first_episodes_counts_each_worlds_first_episode_only():
    """The counting both sides of benchmarks/physics/legged_returns.py share: rewards up to each world's first end,
    a fall told from a time-out, nothing after it (the world's next episode) counted."""
    import torch

    from benchmarks.physics.first_episodes import first_episodes

    ends = {0: (2, "fall"), 1: (4, "time"), 2: (3, "fall")}  # world: (the step its first episode ends, how)
    t = {"now": 0}

    def step(actions):
        t["now"] += 1
        terminated = torch.tensor([ends[w] == (t["now"], "fall") for w in range(3)])
        truncated = torch.tensor([ends[w] == (t["now"], "time") for w in range(3)])
        return actions, torch.full((3,), float(t["now"])), terminated, truncated, {}

    got = first_episodes(step, lambda obs: obs, torch.zeros(3, 1), 3, max_steps=10)
    assert got["returns"] == [1 + 2, 1 + 2 + 3 + 4, 1 + 2 + 3]
    assert got["lengths"] == [2, 4, 3] and got["fell"] == [True, False, True]
    assert t["now"] == 4  # stopped once every world had ended


def test_a_summary_reports_at_its_own_mark_and_refuses_another(out, tmp_path, capsys):
    summary = sbs.summarize(str(out), mark=445.0)
    path = tmp_path / "summary.json"
    path.write_text(json.dumps(summary))
    assert sbs.main(["--report", str(path)]) == 0
    assert "| 445 (the mark) |" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        sbs.main(["--report", str(path), "--mark", "600"])
    assert "summarised at 445 s" in capsys.readouterr().err


@pytest.mark.parametrize("ours_first", [False, True])
def test_on_one_gpu_mjlab_and_warpgyms_seeds_take_turns_its_packages_on_its_command_alone(tmp_path, monkeypatch,
                                                                                           ours_first):
    # stand-ins for both interpreters: each prints its time, its MuJoCo setting, its path and its arguments
    fake = tmp_path / "fake-python"
    fake.write_text('#!/bin/sh\nsleep 0.2\necho "$(date +%s.%N)|${MUJOCO_GL:-unset}|$PYTHONPATH|$*"\n')
    fake.chmod(0o755)
    monkeypatch.setattr(sbs.sys, "executable", str(fake))
    monkeypatch.setenv("CUDA_VISIBLE_DEVICES", "0")
    monkeypatch.delenv("MUJOCO_GL", raising=False)  # set by other tests' renderers: only mjlab's command sets it here
    run = tmp_path / "run"
    sbs.main(["--out", str(run), "--start", "--one-gpu", "--tasks", "G1VelocityFlat-v0", "--speed-envs",
              "--mjlab-python", str(fake), "--mjlab-path", "/mj/site", "--seeds", "3", "4", "--ours-budget", "5"]
             + (["--ours-first"] if ours_first else []))
    sbs.main(["--out", str(run), "--wait", "30"])
    jobs = json.loads((run / "jobs.json").read_text())
    assert jobs["one_gpu"] and {j["framework"] for j in jobs["jobs"]} == {"mjlab", "warpgym"}
    assert len({j["pid"] for j in jobs["jobs"]}) == 1  # one shell, so its end is both trainings' end
    mj = (run / "train-mjlab-G1VelocityFlat-v0.log").read_text().split("|")
    ours = [line.split("|") for line in (run / "train-warpgym-G1VelocityFlat-v0.log").read_text().splitlines()]
    assert mj[1] == "disable" and mj[2].split(":")[1] == "/mj/site" and "Mjlab-Velocity-Flat-Unitree-G1" in mj[3]
    assert [o[1] for o in ours] == ["unset", "unset"] and "/mj/site" not in ours[0][2]
    assert float(ours[0][0]) < float(ours[1][0])  # the seeds in order
    assert (float(mj[0]) > float(ours[1][0])) == ours_first  # mjlab before them or, --ours-first, after
    # mjlab's clock: the moment its turn came, written down just before its process started
    started = float((run / "started-mjlab-G1VelocityFlat-v0").read_text())
    assert 0.0 < float(mj[0]) - started < 5.0
    assert "--seed 3" in ours[0][3] and "--seed 4" in ours[1][3]


def test_one_gpu_refuses_two_tasks(tmp_path):
    with pytest.raises(SystemExit, match="one task per --out folder"):
        sbs.main(["--out", str(tmp_path), "--start", "--one-gpu", "--speed-envs", "--tasks", "G1VelocityFlat-v0",
                  "Go1VelocityFlat-v0"])
