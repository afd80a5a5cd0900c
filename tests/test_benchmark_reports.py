"""benchmarks/learning/learners.py --report: the rows of several earlier runs in one table."""

import copy
import json
import os
import re
import shutil

import pytest

from benchmarks.learning import learners as cmp

COMMON = {"device": "NVIDIA H200", "num_envs": 4096, "seconds": 180.0, "hparams": "preset", "settings": {"Ant": {}}}


def published(root: str) -> str:
    """docs/benchmarks.md (today's figures) and docs/history.md (the log, where superseded and investigative rows
    went): a generated row must stand on one of them, word for word."""
    text = ""
    for page in ("benchmarks.md", "history.md"):
        with open(os.path.join(root, "docs", page)) as f:
            text += f.read() + "\n"
    return text

def write(out, date, rows, **change):
    os.makedirs(out)
    with open(os.path.join(out, "comparison.json"), "w") as f:
        json.dump({**COMMON, **change, "date": date, "rows": rows}, f)
    return str(out)


def row(learner, run_dir, sps, **extra):
    return {"task": "Ant", "learner": learner, "gpus": 1, "run_dir": run_dir, "samples_per_s": sps,
            "time_to_target_s": None, **extra}


def test_rows_of_two_runs_made_alike_are_reported_together(tmp_path):
    first = write(tmp_path / "a", "2026-11-23", [row("warpgym", "/gpu/cmp/Ant-warpgym-1gpu", 1.1e6),
                                                 row("rllib", "/gpu/cmp/Ant-rllib-1gpu", 6.9e3)])
    second = write(tmp_path / "b", "2026-11-24", [row("rllib", "/gpu/cmp8/Ant-rllib-1gpu", 2.3e4, env_runners=8)])
    doc = cmp.merged_reports([first, second])
    assert [r["run_dir"] for r in doc["rows"]] == [os.path.join(first, "Ant-warpgym-1gpu"),
                                                   os.path.join(first, "Ant-rllib-1gpu"),
                                                   os.path.join(second, "Ant-rllib-1gpu")]
    assert doc["dates"] == ["2026-11-23", "2026-11-24"]
    assert "rows of 2 script runs (2026-11-23, 2026-11-24)" in cmp.table(doc)
    text = cmp.table(doc)
    assert "| Ant | RLlib PPO, 1 GPU | 0.007 M |" in text
    assert "| Ant | RLlib PPO, 1 GPU, 8 env runners | 0.023 M |" in text
    doc["rows"][0].update(cpu_use_pct=4.3, cpu_cores=64, gpu_util_pct=100.0)  # rows made since know their host's cores
    assert cmp.table(doc).splitlines()[4].endswith("| 100 % | 4 % of 64 |")


def test_a_comparison_on_named_gpus_runs_and_samples_those_gpus(tmp_path, monkeypatch):
    """Under CUDA_VISIBLE_DEVICES=2,3 a 2-GPU comparison gives its child GPUs 2 and 3 (in nvidia-smi's order)
    and reads the use of those two only, so that two comparisons can share a 4-GPU host; the row records which."""
    import time

    import torch

    children, smi = [], []

    class Done:
        returncode, stdout = 0, "40\n60\n"

    def fake_run(cmd, **kw):
        if cmd[0] == "nvidia-smi":
            smi.append(cmd[cmd.index("-i") + 1])
        else:
            children.append((kw["env"]["CUDA_VISIBLE_DEVICES"], kw["env"]["CUDA_DEVICE_ORDER"]))
        return Done()

    monkeypatch.setattr(cmp.subprocess, "run", fake_run)
    with cmp.Usage(["2", "3"], every=0.01) as usage:
        time.sleep(0.2)
    assert smi and set(smi) == {"2,3"} and usage.summary()["gpu_util_pct"] == 50.0

    monkeypatch.setenv("CUDA_VISIBLE_DEVICES", "2,3")
    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(torch.cuda, "get_device_name", lambda i=0: "NVIDIA H200")
    monkeypatch.setattr(cmp, "figures", lambda doc, out: [])
    monkeypatch.setattr(cmp, "row_of", lambda task, learner, gpus, run_dir, wall, rc, use: {
        "task": task, "learner": learner, "gpus": gpus, "run_dir": run_dir, "rc": rc})
    out = str(tmp_path / "cmp")
    args = ["--out", out, "--tasks", "Ant", "--gpus", "2", "--learners", "rllib", "--seconds", "1"]
    assert cmp.main(args) == 0
    assert children == [("2,3", "PCI_BUS_ID")]
    with open(os.path.join(out, "comparison.json")) as f:
        assert json.load(f)["rows"][0]["gpu_ids"] == ["2", "3"]
    monkeypatch.setenv("CUDA_VISIBLE_DEVICES", "2")
    with pytest.raises(SystemExit, match="CUDA_VISIBLE_DEVICES=2 gives this process 1"):
        cmp.main(args)


def test_runs_made_differently_are_refused_by_name(tmp_path):
    first = write(tmp_path / "a", "2026-11-24", [row("warpgym", "/x/Ant-warpgym-1gpu", 1.1e6)])
    other = write(tmp_path / "b", "2026-11-24", [row("rllib", "/x/Ant-rllib-1gpu", 2e4)], num_envs=1024, seconds=60.0)
    with pytest.raises(ValueError, match=r"differ from .* in num_envs, seconds"):
        cmp.merged_reports([first, other])
    # one task's run beside a two-task run joins where the shared task ran alike, and is refused where it did not
    both = write(tmp_path / "c", "2026-11-27", [row("rllib", "/x/Ant-rllib-2gpu", 1e4)],
                 settings={"Ant": {}, "Humanoid": {"horizon_len": 32}})
    assert set(cmp.merged_reports([first, both])["settings"]) == {"Ant", "Humanoid"}
    longer = write(tmp_path / "d", "2026-11-27", [row("rllib", "/x/Ant-rllib-2gpu", 1e4)],
                   settings={"Ant": {"horizon_len": 32}})
    with pytest.raises(ValueError, match="in Ant's settings"):
        cmp.merged_reports([first, longer])


def test_suite_learning_report_merges_runs_made_alike_and_refuses_others(tmp_path, capsys):
    from benchmarks.learning import suite_learning as sl

    def doc(folder, task, seed, scale=1.0, gpu="NVIDIA H100 80GB HBM3", hit=True, **capture):
        os.makedirs(folder, exist_ok=True)
        marks = list(sl.marks_of(task, scale))
        run = {"task": task, "seed": seed, "budget_s": marks[-1], "marks_s": marks, "samples": 2.4e8,
               "num_envs": 4096, "samples_per_s": 4.0e5, "reference": sl.REFERENCE.get(task), "device": "cuda:0",
               "curve": [[30.0 + 10 * seed, 131072, 10.0], [31.0 + 10 * seed, 262144, 20.0]],
               "first_eval_reaching": {"target": {"time_s": 420.0, "samples": 1.7e8} if hit else None,
                                       "half": {"time_s": 180.0, "samples": 7e7}},
               "scored": [{"mark_s": m, "time_s": m + 1, "samples": 1e6, "gymnasium_return": 1000.0 * (i + 1),
                           "warpgym_return": 1000.0 * (i + 1), "gymnasium_over_warpgym": 0.97 + 0.01 * i}
                          for i, m in enumerate(marks)], **capture}
        with open(os.path.join(folder, f"{task}-seed{seed}.json"), "w") as f:
            json.dump({"meta": {"gpu": gpu, "scale": scale, "date": "2026-11-26", "command": "x"}, "run": run}, f)

    doc(tmp_path / "a", "Hopper-v5", 0, rollout_graph="step")
    doc(tmp_path / "b", "Hopper-v5", 1, hit=False, rollout_graph="step")
    assert sl.report([str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    table = capsys.readouterr().out
    # both seeds in one row: the marks' mean returns, the reference reached by one seed of two, the lowest ratio
    # (the scores rise 1000 a mark: 3000 at 3 minutes, 4000 at 5; Gymnasium's env judges the first mark at 3542.2)
    assert ("| Hopper-v5 | 2 | 1 min: 1000; 2 min: 2000; 3 min: 3000; 5 min: 4000; 10 min: 5000 | 3542.2 | "
            "7.0, not reached (3.0, 3.0) | 5, 5 | 35 s | 240.0 M |") in table and "†" not in table
    assert "by the 3-minute mark in every seed: 0 of 1 rows (none)" in table
    # a seed from before the step capture (no rollout_graph in its JSON): its start took the whole rollout's capture
    doc(tmp_path / "b", "Hopper-v5", 1, hit=False)
    assert sl.report([str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    table = capsys.readouterr().out
    assert "| 35 s † | 240.0 M |" in table and "† the whole rollout captured as one graph" in table
    assert next(line for line in table.splitlines() if line.startswith("| Hopper-v5")).endswith("| 0.970 |")
    # the first iteration as summary.json has it, where the run holds it: the curve starts with the first
    # iteration that finished an episode
    doc(tmp_path / "a", "Hopper-v5", 0, rollout_graph="step", first_iteration_s=6.0)
    doc(tmp_path / "b", "Hopper-v5", 1, hit=False, rollout_graph="step", first_iteration_s=8.0)
    assert sl.report([str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    assert "| 7 s | 240.0 M |" in capsys.readouterr().out
    assert "SLM-Lab's on v5 for Pusher and HumanoidStandup" in table  # where the two figures not Tianshou's come from
    doc(tmp_path / "c", "Hopper-v5", 2, scale=0.1)
    with pytest.raises(SystemExit, match="made differently"):
        sl.report([str(tmp_path / "a"), str(tmp_path / "c")])
    assert sl.half(-2.6) == -5.2 and sl.half(5850.0) == 2925.0
    # a row made on another card stands beside the others, marked in both tables and named in a note; the header
    # names the card most rows ran on
    for seed in (0, 1):
        doc(tmp_path / "d", "Walker2d-v5", seed, rollout_graph="step")
        doc(tmp_path / "e", "Swimmer-v5", seed, gpu="NVIDIA H200", rollout_graph="step")
    assert sl.report([str(tmp_path / "a"), str(tmp_path / "b"), str(tmp_path / "d"), str(tmp_path / "e")]) == 0
    out = capsys.readouterr().out
    assert out.startswith("warpgym PPO, NVIDIA H100 80GB HBM3;")
    assert [line.split(" | ")[0] for line in out.splitlines() if line.startswith("| Swimmer-v5")] == \
        ["| Swimmer-v5 ‡"] * 2  # the table's row and the README's
    assert not [line for line in out.splitlines() if line.startswith(("| Hopper-v5 ‡", "| Walker2d-v5 ‡"))]
    assert "‡ on NVIDIA H200: Swimmer-v5 (the other rows: NVIDIA H100 80GB HBM3)" in out
    # one row's seeds on two cards: its minutes to the figure would be neither card's
    doc(tmp_path / "e", "Walker2d-v5", 2, gpu="NVIDIA H200", rollout_graph="step")
    with pytest.raises(SystemExit, match=r"the seeds of Walker2d-v5 ran on different cards"):
        sl.report([str(tmp_path / "d"), str(tmp_path / "e")])


def test_suite_learning_gives_a_candidate_presets_runs_a_row_of_their_own(tmp_path, capsys, monkeypatch):
    """``--config gamma=0.995``: the setting reaches warpgym train, names the run's JSON and folder, and the table
    and the README's table give those runs their own row beside the preset's; a wrong setting stops the command
    before any run with one line naming it."""
    from benchmarks.learning import suite_learning as sl

    calls = []
    monkeypatch.setattr(sl, "train_in_parts", lambda args, run_dir, budget, device: calls.append((args, run_dir)) or 1)
    run = sl.train_one("Hopper-v5", 2, str(tmp_path), 1.0, "cpu", config=("gamma=0.995",))
    assert calls[0][0][:6] == ["--task", "Hopper-v5", "--seed", "2", "--config", "gamma=0.995"]
    assert os.path.basename(calls[0][1]) == "Hopper-v5-gamma=0.995-seed2" and run["config"] == ["gamma=0.995"]
    assert sl.run_stem("Hopper-v5", 0) == "Hopper-v5-seed0" and sl.run_stem("Ant-v5", 1, ("net_dims=64,64",)) == \
        "Ant-v5-net_dims=64x64-seed1"
    marks = list(sl.marks_of("Hopper-v5", 1.0))

    def doc(seed, config, value):
        run = {"task": "Hopper-v5", "seed": seed, "config": config, "marks_s": marks, "samples": 1e8,
               "samples_per_s": 4e5, "reference": 3542.2, "curve": [[10.0, 1e6, 1.0]], "first_iteration_s": 7.0,
               "rollout_graph": "step", "evals": [{"time_s": 200.0, "samples": 1e7, "eval/return": value}],
               "scored": [{"mark_s": m, "time_s": m, "samples": 1e6, "gymnasium_return": value,
                           "warpgym_return": value, "gymnasium_over_warpgym": 1.0} for m in marks]}
        path = tmp_path / f"{sl.run_stem('Hopper-v5', seed, tuple(config))}.json"
        path.write_text(json.dumps({"meta": {"gpu": "NVIDIA H200", "scale": 1.0, "date": "2026-11-27"}, "run": run}))

    doc(0, [], 2600.0)
    doc(0, ["gamma=0.995"], 3600.0)
    doc(1, ["gamma=0.995"], 3500.0)
    assert sl.report([str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "| Hopper-v5 | 1 | 1 min: 2600; 2 min: 2600; 3 min: 2600; 5 min: 2600; 10 min: 2600 | 3542.2 | not reached (" \
        in out
    assert "| Hopper-v5 (gamma=0.995) | 2 | 1 min: 3550; 2 min: 3550; 3 min: 3550; 5 min: 3550; 10 min: 3550 | 3542.2 | " \
           "3.3, not reached (" in out
    # the README's row: the mean of the seeds' last scores, their range, each seed's minutes to the figure
    assert "| Hopper-v5 (gamma=0.995) | **3550** (3500 to 3600) | 3542.2 (Tianshou, v3) | 3.3, not reached |" in out
    assert sl.finished(str(tmp_path), "Hopper-v5", 1, ("gamma=0.995",))
    assert not sl.finished(str(tmp_path), "Hopper-v5", 1)
    runs, _ = sl.load_runs([str(tmp_path)], "")  # the curves: a panel each, not the two rows' seeds in one band
    assert sorted(sl.figure_tasks(runs, [])) == ["Hopper-v5", "Hopper-v5 (gamma=0.995)"]
    assert sl.report([str(tmp_path)], str(tmp_path / "curves.png")) == 0 and (tmp_path / "curves-samples.png").exists()
    capsys.readouterr()
    played = []  # --score finds the kept policies in the run's own folder
    monkeypatch.setattr(sl, "play", lambda path, *a, **k: played.append(path) or {
        "gymnasium_return": 1.0, "warpgym_return": 1.0, "gymnasium_over_warpgym": 1.0, "episodes": 30, "seeds": [0]})
    sl.score_run({"task": "Hopper-v5", "seed": 1, "config": ["gamma=0.995"], "scored": [],
                  "kept": [{"mark_s": 60.0, "time_s": 61.0, "samples": 1, "checkpoint": "checkpoint-9.pt"}]},
                 str(tmp_path), 10, "cpu")
    assert played and played[0] == os.path.join(str(tmp_path), "runs", "Hopper-v5-gamma=0.995-seed1", "checkpoint-9.pt")
    with pytest.raises(SystemExit) as stop:
        sl.main(["--out", str(tmp_path), "--tasks", "Hopper-v5", "--config", "gamma=abc", "--device", "cpu"])
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert stop.value.code == 2 and "--config" in err and "gamma" in err and "abc" in err
    with pytest.raises(SystemExit) as stop:
        sl.main(["--out", str(tmp_path), "--tasks", "Hopper-v5", "--config", "gama=0.9", "--device", "cpu"])
    assert stop.value.code == 2 and "'gama' is not a PPO setting" in capsys.readouterr().err
    with pytest.raises(SystemExit) as stop:  # the preset's own value is no candidate
        sl.main(["--out", str(tmp_path), "--tasks", "Hopper-v5", "--config", "gamma=0.999", "--device", "cpu"])
    assert stop.value.code == 2 and "--config gamma=0.999: Hopper-v5's preset holds it already; leave it out" in \
        capsys.readouterr().err


def test_suite_learning_promotes_a_candidates_rows_once_the_preset_holds_its_settings(tmp_path, capsys, monkeypatch):
    """``--promote OUT --into DIR``: refused while warpgym/tasks/presets.py's preset lacks the candidate's settings, while a run
    is not scored, and while DIR holds the rows they replace; then written as the preset's rows (``config`` empty, the
    settings kept as ``made_with``), which the table names as the task alone and --score and suite_versions still
    find in the run's own folder."""
    from benchmarks.learning import suite_learning as sl
    from benchmarks.learning import suite_versions as sv

    src, dest = tmp_path / "out", tmp_path / "table"
    os.makedirs(src)
    os.makedirs(dest)
    marks = list(sl.marks_of("Swimmer-v5", 1.0))

    def doc(folder, seed, config, scored=True):
        run = {"task": "Swimmer-v5", "seed": seed, "config": config, "marks_s": marks, "samples": 1e8,
               "samples_per_s": 5e5, "reference": 44.4, "curve": [[10.0, 1e6, 1.0]], "first_iteration_s": 7.0,
               "rollout_graph": "step", "evals": [{"time_s": 130.0, "samples": 1e7, "eval/return": 60.0}],
               "kept": [{"mark_s": 600.0, "checkpoint": "checkpoint-7.pt"}],
               "scored": [{"mark_s": m, "time_s": m, "samples": 1e6, "gymnasium_return": 60.0 + seed,
                           "warpgym_return": 60.0, "gymnasium_over_warpgym": 1.0} for m in marks] if scored else []}
        path = folder / f"{sl.run_stem('Swimmer-v5', seed, tuple(config))}.json"
        path.write_text(json.dumps({"meta": {"gpu": "NVIDIA H200", "scale": 1.0, "date": "2026-11-27"}, "run": run}))
        return path

    # a discount no preset has: the candidate is refused until the (patched) preset takes it
    from warpgym.tasks.presets import PRESETS

    assert PRESETS["Swimmer-v5"].get("gamma") != 0.991
    for seed in (0, 1):
        doc(src, seed, ["gamma=0.991"])
    doc(dest, 0, [])  # the row the candidate would replace
    argv = ["--promote", str(src), "--into", str(dest)]
    with pytest.raises(SystemExit, match="which Swimmer-v5's preset in warpgym/tasks/presets.py does not hold; change the "
                                         "preset first"):
        sl.main(argv)
    monkeypatch.setitem(PRESETS["Swimmer-v5"], "gamma", 0.991)  # the task's registry entry holds this very dict
    with pytest.raises(SystemExit, match=r"still holds Swimmer-v5's rows \(Swimmer-v5-seed0.json\); move them to "
                                         ".*superseded/ first"):
        sl.main(argv)
    os.makedirs(dest / "superseded")
    os.rename(dest / "Swimmer-v5-seed0.json", dest / "superseded" / "Swimmer-v5-seed0-gamma-0.9999.json")
    unscored = doc(src, 2, ["gamma=0.991"], scored=False)
    with pytest.raises(SystemExit, match="is not a scored run; score it first"):
        sl.main(argv)
    os.remove(unscored)
    with pytest.raises(SystemExit) as stop:
        sl.main(["--promote", str(src)])
    assert stop.value.code == 2 and "--into DIR" in capsys.readouterr().err
    other = tmp_path / "out2"  # a second lane of the same candidate: its seeds join, a seed twice is refused
    os.makedirs(other)
    twin = doc(other, 1, ["gamma=0.991"])
    with pytest.raises(SystemExit, match="are both Swimmer-v5's seed 1; promote one"):
        sl.main(["--promote", str(src), str(other), "--into", str(dest)])
    os.remove(twin)
    doc(other, 3, ["gamma=0.991"])
    assert sl.main(["--promote", str(src), str(other), "--into", str(dest)]) == 0
    assert sorted(os.listdir(dest)) == ["Swimmer-v5-seed0.json", "Swimmer-v5-seed1.json", "Swimmer-v5-seed3.json",
                                        "superseded"]
    os.remove(dest / "Swimmer-v5-seed3.json")
    promoted = json.loads((dest / "Swimmer-v5-seed1.json").read_text())
    assert promoted["run"]["config"] == [] and promoted["run"]["made_with"] == ["gamma=0.991"]
    assert promoted["meta"]["promoted"] and promoted["run"]["scored"][-1]["gymnasium_return"] == 61.0
    capsys.readouterr()
    assert sl.report([str(dest)]) == 0
    assert "| Swimmer-v5 | **60.5** (60.0 to 61.0) | 44.4 (Tianshou, v3) | 2.2, 2.2 |" in capsys.readouterr().out
    # the promoted rows' policies are where the candidate's runs left them
    assert sl.made_with(promoted["run"]) == ("gamma=0.991",)
    os.makedirs(dest / "runs" / "Swimmer-v5-gamma=0.991-seed0")
    os.makedirs(dest / "runs" / "Swimmer-v5-gamma=0.991-seed1")
    played = []
    monkeypatch.setattr(sv, "play", lambda path, *a, **k: played.append(os.path.relpath(path, dest)) or {
        "episodes": 30, "gymnasium_return": 60.0, "gymnasium_length": 1000.0, "v4_return": 60.0, "v4_length": 1000.0,
        "v4_over_v5": 1.0, "gymnasium_terms": {}, "v4_terms": {}})
    for seed in (0, 1):
        (dest / "runs" / f"Swimmer-v5-gamma=0.991-seed{seed}" / "checkpoint-7.pt").write_bytes(b"")
    rows = sv.score([str(dest)], 10, "cpu")
    assert sorted(played) == [os.path.join("runs", f"Swimmer-v5-gamma=0.991-seed{s}", "checkpoint-7.pt") for s in (0, 1)]
    assert {r["task"] for r in rows} == {"Swimmer-v5"}


def test_suite_versions_update_replaces_the_rows_of_the_runs_tasks_where_they_stood(monkeypatch, tmp_path, capsys):
    """``--update JSON``: an earlier table's rows kept, those of the tasks the runs have replaced in place, a new task
    last; the earlier table's meta kept under ``updated``; a file that is no such table is one line naming it."""
    from benchmarks.learning import suite_versions as sv

    def r(task, seed, value):
        return {"task": task, "seed": seed, "mark_s": 600.0, "v5_return": value, "v4_return": value,
                "v4_over_v5": 1.0, "v5_length": 1000.0, "v4_length": 1000.0, "v5_terms": {}, "v4_terms": {}}

    old = [r("Reacher-v5", 0, -4.0), r("Hopper-v5", 0, 2000.0), r("Hopper-v5", 1, 2100.0), r("Swimmer-v5", 0, 40.0)]
    new = [r("Hopper-v5", s, 3700.0) for s in range(4)] + [r("Walker2d-v5", 0, 6000.0)]
    got = sv.updated(old, new)
    assert [(x["task"], x["seed"], x["v5_return"]) for x in got] == [
        ("Reacher-v5", 0, -4.0), *[("Hopper-v5", s, 3700.0) for s in range(4)], ("Swimmer-v5", 0, 40.0),
        ("Walker2d-v5", 0, 6000.0)]
    table = tmp_path / "versions.json"
    table.write_text(json.dumps({"meta": {"date": "2026-11-26", "command": "earlier"}, "rows": old}))
    monkeypatch.setattr(sv, "score", lambda folders, episodes, device: new[:4])
    assert sv.main(["--runs", str(tmp_path), "--update", str(table)]) == 0
    written = json.loads(table.read_text())
    assert [x["task"] for x in written["rows"]] == ["Reacher-v5"] + ["Hopper-v5"] * 4 + ["Swimmer-v5"]
    assert written["meta"]["updated"] == {"date": "2026-11-26", "command": "earlier"}
    (tmp_path / "bad.json").write_text("[]")
    with pytest.raises(SystemExit) as stop:
        sv.main(["--runs", str(tmp_path), "--update", str(tmp_path / "bad.json")])
    assert stop.value.code == 2 and "--update" in capsys.readouterr().err
    (tmp_path / "bad.json").write_text('{"rows": [')  # a damaged or missing file: harness.read_report's one line
    with pytest.raises(SystemExit, match=r"--update .*bad.json: cannot be read as JSON"):
        sv.main(["--runs", str(tmp_path), "--update", str(tmp_path / "bad.json")])
    with pytest.raises(SystemExit, match=r"--update .*nowhere.json: no such file; pass the file an earlier --json"):
        sv.main(["--runs", str(tmp_path), "--update", str(tmp_path / "nowhere.json")])


def test_suite_learning_reads_minutes_to_the_reference_from_the_runs_evaluations():
    """A run keeps its evaluations, so the table's minutes follow REFERENCE as it stands now, not the figure
    (here a rounded 9360 that no policy can reach) the run was made with."""
    from benchmarks.learning import suite_learning as sl

    evals = [{"time_s": 77.0, "samples": 1e7, "eval/return": 9068.7},
             {"time_s": 137.0, "samples": 5e7, "eval/return": 9359.8}]
    run = {"task": "InvertedDoublePendulum-v5", "seed": 0, "marks_s": [60.0], "samples": 8e7, "samples_per_s": 5e5,
           "reference": 9360.0, "first_eval_reaching": {"target": None, "half": None}, "scored": [], "evals": evals}
    row = next(line for line in sl.table([run]).splitlines() if line.startswith("| InvertedDoublePendulum"))
    assert f"| {sl.REFERENCE['InvertedDoublePendulum-v5']} | 2.3 (1.3) | - |" in row  # no policy scored yet
    evals[1]["eval/return"] = 9359.0  # below Tianshou's 9359.5
    assert "not reached (1.3)" in sl.table([run])
    # the lowest ratio, and where its policy was also played from nudged starts, Gymnasium against itself
    run["scored"] = [{"mark_s": 60.0, "gymnasium_return": 940.2, "gymnasium_over_warpgym": 0.9402, "nudge": 1e-9,
                      "gymnasium_over_gymnasium_nudged": 0.9402},
                     {"mark_s": 120.0, "gymnasium_return": 9000.0, "gymnasium_over_warpgym": 0.99}]
    assert sl.table([run]).endswith("| 0.940 (Gymnasium / itself 1e-09 apart: 0.940) |")


def test_suite_learning_scores_a_policy_below_the_goal_again_on_more_episodes_and_nudged_starts(monkeypatch, tmp_path):
    """Below 0.95 on 30 episodes a policy is played again on 100 (seeds 0-9) with the nudge; the table shows that
    result. A run scored before that rule is rescored only where it fell below."""
    from benchmarks.learning import suite_learning as sl

    from warpgym.cli import eval as eval_command

    calls = []

    def fake_eval(args):
        seeds = args[args.index("--seeds") + 1:args.index("--json")]
        calls.append((os.path.basename(args[0]), seeds, "--nudge" in args))
        low = "checkpoint-1.pt" in args[0] and len(seeds) == 3
        result = {"gymnasium_return": 90.0 if low else 99.0, "warpgym_return": 100.0, "episodes": 10 * len(seeds),
                  "gymnasium_over_warpgym": 0.9 if low else 0.99}
        if "--nudge" in args:
            result |= {"nudge": 1e-9, "gymnasium_over_gymnasium_nudged": 1.01}
        with open(args[args.index("--json") + 1], "w") as f:
            json.dump(result, f)

    monkeypatch.setattr(eval_command, "main", fake_eval)
    os.makedirs(tmp_path / "runs" / "Ant-v5-seed0")
    run = {"task": "Ant-v5", "seed": 0, "scored": [],
           "kept": [{"mark_s": m, "time_s": m, "samples": 1, "checkpoint": f"checkpoint-{i}.pt"}
                    for i, m in enumerate((60.0, 120.0))]}
    assert sl.needs_scoring(run)
    scored = sl.score_run(run, str(tmp_path), 10, "cpu")["scored"]
    assert calls == [("checkpoint-0.pt", ["0", "1", "2"], False), ("checkpoint-1.pt", ["0", "1", "2"], False),
                     ("checkpoint-1.pt", [str(k) for k in range(10)], True)]
    assert [s["episodes"] for s in scored] == [30, 100] and scored[1]["gymnasium_over_warpgym"] == 0.99
    assert scored[1]["gymnasium_over_gymnasium_nudged"] == 1.01 and not sl.needs_scoring({**run, "scored": scored})
    # scored before the rule: the low policy alone is played again, straight on 100 episodes
    old = [{k: v for k, v in s.items() if k != "seeds"} for s in scored]
    old[1] |= {"gymnasium_over_warpgym": 0.9, "episodes": 30}
    calls.clear()
    assert sl.needs_scoring({**run, "scored": old})
    again = sl.score_run({**run, "scored": old}, str(tmp_path), 10, "cpu")["scored"]
    assert calls == [("checkpoint-1.pt", [str(k) for k in range(10)], True)]
    assert again[0] == old[0] and again[1]["episodes"] == 100


def test_suite_learning_gives_each_gpus_process_the_arguments_less_the_spread():
    """--gpus N starts one process per seed: each gets every argument but --gpus and --seeds (its own seed is
    added), whichever form they were written in."""
    from benchmarks.learning import suite_learning as sl

    argv = ["--out", "O", "--seeds", "0", "1", "--tasks", "Ant-v5", "Hopper-v5", "--gpus=2", "--no-score"]
    assert sl.without(argv, ("--gpus", "--seeds")) == ["--out", "O", "--tasks", "Ant-v5", "Hopper-v5", "--no-score"]
    assert sl.without(["--gpus", "2", "--seeds=3", "--out", "O"], ("--gpus", "--seeds")) == ["--out", "O"]


def test_suite_learning_report_sets_sb3_beside_warpgym_and_draws_both(tmp_path, capsys):
    """SB3's runs (suite_sb3.py's JSON) get their own table, with no Gymnasium / warpgym ratio, and
    their curves join warpgym's in both figures."""
    from benchmarks.learning import suite_learning as sl

    marks = list(sl.MARKS["long"])

    def run(seed, curve, speed):
        return {"task": "Ant-v5", "seed": seed, "budget_s": 600.0, "marks_s": marks, "samples": curve[-1][1],
                "samples_per_s": speed, "reference": 5850.0, "first_eval_reaching": {"target": None, "half": None},
                "curve": curve, "scored": [{"mark_s": m, "time_s": m, "samples": 1e3 * m, "gymnasium_return": m,
                                            "warpgym_return": m, "gymnasium_over_warpgym": 1.0} for m in marks]}

    for name, meta, speed in (("Ant-v5-seed0.json", {"gpu": "NVIDIA H100 80GB HBM3"}, 2.6e5),
                              ("sb3-Ant-v5-seed0.json", {"cpu": "Intel Xeon"}, 550.0)):
        r = run(0, [[t, 1000 * t, t / 10] for t in range(1, 600, 7)], speed)
        if name.startswith("sb3"):
            for s in r["scored"]:
                del s["warpgym_return"], s["gymnasium_over_warpgym"]
        with open(tmp_path / name, "w") as f:
            json.dump({"meta": {**meta, "scale": 1.0}, "run": r}, f)
    figure = str(tmp_path / "curves.png")
    assert sl.report([str(tmp_path)], figure) == 0
    out = capsys.readouterr().out
    warpgym_table, sb3_table = out.split("Stable-Baselines3")
    assert "| Ant-v5 | 1 | 1 min: 60.0; 2 min: 120; 3 min: 180; 5 min: 300; 10 min: 600 |" in warpgym_table
    ant_row = next(line for line in warpgym_table.splitlines() if line.startswith("| Ant-v5"))
    assert ant_row.endswith("| 0.26 M | 1.000 |")
    assert "Intel Xeon" in sb3_table and sb3_table.rstrip().endswith("| 550 | - |")  # samples/s, no ratio
    assert os.path.getsize(figure) > 10_000 and os.path.getsize(str(tmp_path / "curves-samples.png")) > 10_000
    # SB3's tasks that warpgym's runs lack get no panel of their own; alone, SB3's runs are drawn
    hopper = {"task": "Hopper-v5"}
    assert sl.figure_tasks([r], [r, hopper]) == ["Ant-v5"]
    assert sl.figure_tasks([], [r, hopper]) == ["Ant-v5", "Hopper-v5"]


def test_suite_sb3_takes_the_zoos_hyperparameters_as_sb3_does():
    from benchmarks.learning import suite_sb3 as sb
    import torch

    kw, n_envs = sb.hyperparameters("HalfCheetah-v5")
    assert n_envs == 1 and kw["n_steps"] == 512 and kw["policy_kwargs"]["activation_fn"] is torch.nn.ReLU
    assert sb.ZOO["HalfCheetah-v5"]["policy_kwargs"]["activation_fn"] == "relu"  # the table itself stays as written
    assert sb.hyperparameters("Swimmer-v5")[1] == 4 and sb.hyperparameters("Ant-v5") == ({}, 1)
    with pytest.raises(ValueError, match="no RL Zoo hyperparameters for 'Pusher-v5'"):
        sb.hyperparameters("Pusher-v5")
    assert sb.thin(list(range(1000)), 100)[-1] == 999 and len(sb.thin(list(range(1000)), 100)) <= 101


def test_suite_sweep_ranks_combinations_by_their_return_in_gymnasiums_env():
    from benchmarks.learning import suite_sweep as sw

    assert sw.parse_grid(["gamma=0.99,0.995", "net_dims=256x128,64x64"]) == {
        "gamma": ["0.99", "0.995"], "net_dims": ["256,128", "64,64"]}
    with pytest.raises(ValueError, match="NAME=V1,V2"):
        sw.parse_grid(["gamma"])
    cmd = sw.command("Hopper-v5", {"num_envs": "4096", "gamma": "0.995"}, 1, 60.0)
    assert cmd[-4:] == ["--num-envs", "4096", "--config", "gamma=0.995"]
    assert cmd[cmd.index("--time-limit") + 1] == "60.0"

    def row(label, value, ratio, **length):
        return {"label": label, "gymnasium_return": value,
                "runs": [{"seed": 0, "gymnasium_return": value, "ratio": ratio, "samples_per_s": 2e6, **length}]}

    doc = {"rows": [row("gamma=0.99", 900.0, 0.99), row("gamma=0.995", 2400.0, 0.97, gymnasium_length=736.4),
                    {"label": "gamma=0.9", "gymnasium_return": None, "runs": [{"seed": 0, "error": "exit 1"}]}]}
    lines = sw.table(doc).splitlines()
    assert lines[2] == "| 1 | gamma=0.995 | 2400.0 | 2400 | 736 | 2.00 M | 0.970 |"
    assert lines[3] == "| 2 | gamma=0.99 | 900.0 | 900 | - | 2.00 M | 0.990 |"  # a sweep that kept no lengths
    assert lines[4] == "| 3 | gamma=0.9 | failed | failed | - | - | - |"
    # a sweep that recorded when each seed's evaluations reached the task's figure shows the minutes beside the return
    # and, since the median samples/s leaves synchronous evaluations out but counts those beside training in, the
    # samples of the whole budget (the mean of the seeds' runs)
    timed = copy.deepcopy({**doc, "meta": {"task": "Hopper-v5", "seconds": 200.0}})
    # half a second past the 3-minute line reads past it (one decimal made it 3.0, a pass within 3 minutes)
    timed["rows"][0]["runs"][0]["reaching"] = {"target": {"time_s": 180.5, "samples": 1}, "half": None}
    timed["rows"][1]["runs"].append({**timed["rows"][1]["runs"][0], "seed": 1,
                                     "reaching": {"target": None, "half": None}})
    for r, samples in zip(timed["rows"][:2], ([5.5e7], [6e7, 5e7])):
        for run, n in zip(r["runs"], samples):
            run["samples"] = n
    lines = sw.table(timed).splitlines()
    assert "| per seed | minutes to 3542.2 (each seed) | episode length | samples/s | samples in 200 s |" in lines[0]
    assert lines[2] == ("| 1 | gamma=0.995 | 2400.0 | 2400, 2400 | not reached, not reached | 736 | 2.00 M | 55.0 M "
                        "| 0.970 |")
    assert lines[3] == "| 2 | gamma=0.99 | 900.0 | 900 | 3.01 | - | 2.00 M | 55.0 M | 0.990 |"
    assert lines[4] == "| 3 | gamma=0.9 | failed | failed | failed | - | - | - | - |"

    meta = {"task": "Hopper-v5", "seconds": 180.0, "seeds": [1], "gpu": "H100", "date": "2026-11-25", "command": "c"}
    both = sw.merged([{"meta": meta, "rows": doc["rows"][:1]}, {"meta": meta, "rows": doc["rows"][1:]}])
    assert [r["label"] for r in both["rows"]] == ["gamma=0.99", "gamma=0.995", "gamma=0.9"]
    with pytest.raises(SystemExit, match="differ in task, seconds, gpu, scoring"):
        sw.merged([{"meta": meta, "rows": []}, {"meta": {**meta, "seconds": 60.0}, "rows": []}])
    # a grid split over GPUs by seed: each setting's runs join into one row, its mean over all its seeds
    split = [{"meta": {**meta, "seeds": [s]}, "rows": [row("gamma=0.99", 100.0 * (s + 1), 1.0)]} for s in (0, 1)]
    split[1]["rows"][0]["runs"][0]["seed"] = 1
    one = sw.merged(split)
    assert len(one["rows"]) == 1 and one["rows"][0]["gymnasium_return"] == 150.0 and one["meta"]["seeds"] == [0, 1]
    with pytest.raises(SystemExit, match="different seeds, or a seed twice"):
        sw.merged(split + [{"meta": meta, "rows": [row("gamma=0.995", 1.0, 1.0)]}])  # one setting on seed 0 only
    with pytest.raises(SystemExit, match="different seeds, or a seed twice"):
        sw.merged([split[0], split[0]])


def test_suite_sweep_spreads_settings_and_seeds_over_gpus_and_joins_them(monkeypatch, tmp_path):
    """``--gpus N``: one process per setting and seed, on GPUs 0..N-1; their sweeps joined into one row per
    setting, their runs moved beside the joined JSON; a process that wrote nothing is an error row naming its log."""
    import argparse
    import threading

    from benchmarks.learning import suite_sweep as sw

    calls, crashed, again_call = [], [], []
    both_running = threading.Barrier(2, timeout=20)  # the first two children run at once, or the test fails

    def fake_child(cmd, env, **kw):
        out, seed = cmd[cmd.index("--out") + 1], int(cmd[cmd.index("--seeds") + 1])
        grid = [cmd[i + 1] for i, a in enumerate(cmd) if a == "--grid"]
        calls.append((env["CUDA_VISIBLE_DEVICES"], grid, seed, "--no-warm-up" in cmd))
        if len(calls) <= 2 and not again_call:
            try:
                both_running.wait()
            except threading.BrokenBarrierError:
                pass
        if out.endswith("003") and not crashed:
            crashed.append(out)
            return  # crashed before writing anything (the first time)
        os.makedirs(os.path.join(out, "runs", "InvertedPendulum-v5-0"))
        combo = {"net_dims": grid[0].split("=")[1].replace("x", ",")}
        value = 100.0 * seed + (1000.0 if combo["net_dims"] == "64,64" else 0.0)
        run = {"seed": seed, "run_dir": "/root/x/runs/InvertedPendulum-v5-0", "gymnasium_return": value,
               "ratio": 1.0, "samples_per_s": 1e6}
        meta = {"task": "InvertedPendulum-v5", "seconds": 180.0, "seeds": [seed], "gpu": "H100", "date": "d",
                "command": " ".join(cmd), "scoring": {"episodes": 10, "seeds": [0, 1, 2]}}
        with open(os.path.join(out, "sweep-InvertedPendulum-v5.json"), "w") as f:
            json.dump({"meta": meta, "rows": [{"combo": combo, "label": f"net_dims={combo['net_dims']}",
                                               "runs": [run], "gymnasium_return": value}]}, f)

    from benchmarks.harness import gpu_slot

    cores = sorted(os.sched_getaffinity(0))
    with pytest.raises(SystemExit, match=f"{len(cores) + 1} GPUs but only {len(cores)} cores"):
        gpu_slot(0, len(cores) + 1)
    monkeypatch.delenv("CUDA_VISIBLE_DEVICES", raising=False)
    slot = gpu_slot(len(cores) - 1, len(cores))  # the last GPU gets the last core
    assert slot["env"]["CUDA_VISIBLE_DEVICES"] == str(len(cores) - 1)
    # within the GPUs this process was given: its second is the host's GPU 3
    monkeypatch.setenv("CUDA_VISIBLE_DEVICES", "2, 3")
    assert gpu_slot(1, 2)["env"]["CUDA_VISIBLE_DEVICES"] == "3"
    with pytest.raises(SystemExit, match="3 GPUs asked for, but CUDA_VISIBLE_DEVICES=2,3 gives this process 2"):
        gpu_slot(0, 3)
    monkeypatch.delenv("CUDA_VISIBLE_DEVICES")
    monkeypatch.setattr(sw.subprocess, "run", fake_child)
    args = argparse.Namespace(gpus=2, seeds=[0, 1], out=str(tmp_path), task="InvertedPendulum-v5")
    doc = sw.spread(args, {"net_dims": ["64,64", "32,32"]},
                    ["--out", str(tmp_path), "--task", "InvertedPendulum-v5", "--grid", "net_dims=64x64,32x32",
                     "--seeds", "0", "1", "--gpus", "2", "--seconds", "180"])
    assert sorted((g, s) for _, g, s, _ in calls) == [(["net_dims=32x32"], 0), (["net_dims=32x32"], 1),
                                                      (["net_dims=64x64"], 0), (["net_dims=64x64"], 1)]
    # two at a time, one on each GPU
    assert {calls[0][0], calls[1][0]} == {"0", "1"} and not both_running.broken
    assert {gpu for gpu, *_ in calls} == {"0", "1"} and all(warm for *_, warm in calls)
    rows = {r["label"]: r for r in doc["rows"]}
    assert doc["meta"]["seeds"] == [0, 1] and set(rows) == {"net_dims=64,64", "net_dims=32,32"}
    assert rows["net_dims=64,64"]["gymnasium_return"] == 1050.0
    (failed,) = [r for r in rows["net_dims=32,32"]["runs"] if "error" in r]
    assert failed["seed"] == 1 and "parts/003/sweep.log" in failed["error"]
    assert rows["net_dims=32,32"]["gymnasium_return"] == 0.0  # the one seed that wrote
    for r in doc["rows"]:
        for run in r["runs"]:
            if "run_dir" in run:
                assert os.path.dirname(run["run_dir"]) == str(tmp_path / "runs") and os.path.isdir(run["run_dir"])
    # the same command in a later call (the first stopped by a call's limit): only the part that wrote no sweep runs
    # again, and the join finds the runs it moved before
    calls.clear()
    again_call.append(True)  # one part this time: nothing to run beside
    again = sw.spread(args, {"net_dims": ["64,64", "32,32"]},
                      ["--out", str(tmp_path), "--task", "InvertedPendulum-v5", "--grid", "net_dims=64x64,32x32",
                       "--seeds", "0", "1", "--gpus", "2", "--seconds", "180"])
    assert [(g, s) for _, g, s, _ in calls] == [(["net_dims=32x32"], 1)]
    assert {r["label"]: r["gymnasium_return"] for r in again["rows"]} == {"net_dims=64,64": 1050.0,
                                                                        "net_dims=32,32": 50.0}
    assert sw.run_name("Hopper-v5", "gamma=0.999 net_dims=64,64", 3) == "Hopper-v5-gamma=0.999_net_dims=64x64-seed3"


def test_suite_sweep_scores_its_policies_again_and_keeps_the_first_score(monkeypatch, tmp_path):
    """``--score``: each final policy played again with the scoring asked for, from its folder beside the JSON
    (not the path the GPU machine wrote); the row's mean follows; the earlier score stays beside the new."""
    from benchmarks.learning import suite_sweep as sw

    from warpgym.cli import eval as eval_command

    calls = []

    def fake_eval(args):
        seeds = args[args.index("--seeds") + 1:args.index("--json")]
        calls.append((args[0], args[args.index("--episodes") + 1], seeds))
        value = 3000.0 if args[0].endswith("-1") else 2000.0
        with open(args[args.index("--json") + 1], "w") as f:
            json.dump({"gymnasium_return": value, "gymnasium_over_warpgym": 0.98, "gymnasium_length": 700.0}, f)

    monkeypatch.setattr(eval_command, "main", fake_eval)
    for k, name in enumerate(("Hopper-v5-0", "Hopper-v5-1")):
        os.makedirs(tmp_path / "runs" / name)
        (tmp_path / "runs" / name / "checkpoint.pt").write_bytes(b"")
        (tmp_path / "runs" / name / "metrics.jsonl").write_text(
            json.dumps({"time_s": 60.0, "samples": 1, "eval/return": 1800.0 + 2000.0 * k}) + "\n")
    meta = {"task": "Hopper-v5", "seconds": 480.0, "seeds": [0, 1], "gpu": "H200", "date": "2026-11-25", "command": "c"}
    runs = [{"seed": s, "run_dir": f"/root/sw/runs/Hopper-v5-{s}", "gymnasium_return": 1000.0 + s, "ratio": 0.9,
             "samples_per_s": 5e5} for s in (0, 1)]
    path = tmp_path / "sweep-Hopper-v5.json"
    path.write_text(json.dumps({"meta": meta, "rows": [{"label": "anneal_lr=true", "gymnasium_return": 1000.5,
                                                         "runs": runs + [{"seed": 2, "error": "exit 1"}]}]}))
    doc = sw.score_again(str(path), {"episodes": 10, "seeds": [0, 1, 2]}, "cpu")
    assert calls == [(str(tmp_path / "runs" / f"Hopper-v5-{s}"), "10", ["0", "1", "2"]) for s in (0, 1)]
    (row,) = doc["rows"]
    assert row["gymnasium_return"] == 2500.0
    assert [r.get("gymnasium_return") for r in row["runs"]] == [2000.0, 3000.0, None]
    assert row["runs"][1]["first_score"] == {"gymnasium_return": 1001.0, "ratio": 0.9, "episodes": 5, "seeds": [0]}
    # and each run's minutes to the figure (3542.2), from its folder's metrics
    assert [r.get("reaching") for r in row["runs"]] == [{"target": None, "half": {"time_s": 60.0, "samples": 1}},
                                                        {"target": {"time_s": 60.0, "samples": 1},
                                                         "half": {"time_s": 60.0, "samples": 1}}, None]
    assert doc["meta"]["scoring"] == {"episodes": 10, "seeds": [0, 1, 2]}
    path.write_text(json.dumps(doc))  # scored again once more: the first score is still the sweep machine's
    again = sw.score_again(str(path), {"episodes": 20, "seeds": [0]}, "cpu")
    assert again["rows"][0]["runs"][1]["first_score"]["episodes"] == 5 and again["meta"]["scoring"]["episodes"] == 20
    with pytest.raises(SystemExit, match="differ in task, seconds, gpu, scoring"):
        sw.merged([doc, {"meta": meta, "rows": []}])  # 30 episodes beside the old 5: not one table
    os.remove(tmp_path / "runs" / "Hopper-v5-1" / "checkpoint.pt")
    with pytest.raises(SystemExit, match="Hopper-v5-1/checkpoint.pt is missing; copy the sweep's runs/ folder"):
        sw.score_again(str(path), {"episodes": 10, "seeds": [0]}, "cpu")


def test_suite_sweep_times_each_seed_to_the_tasks_figure_from_its_runs_metrics(tmp_path):
    """``--times`` (and every sweep from 2026-11-27 on): each run's first evaluation at the task's published figure and
    at half of it, read from the metrics in its folder beside the JSON, where no checkpoint came back."""
    from benchmarks.learning import suite_sweep as sw

    evals = {"Walker2d-v5-0": [(77.0, 2360.0), (137.0, 4962.0), (198.0, 5421.0)],
             "Walker2d-v5-1": [(78.0, 984.0), (138.0, 1862.0), (199.0, 2400.0)]}
    for name, points in evals.items():
        os.makedirs(tmp_path / "runs" / name)
        with open(tmp_path / "runs" / name / "metrics.jsonl", "w") as f:
            for i, (t, ret) in enumerate(points):
                f.write(json.dumps({"iteration": i, "time_s": t - 1.0, "samples": 10 * i}) + "\n")
                f.write(json.dumps({"iteration": i, "time_s": t, "samples": 10 * i + 5, "eval/return": ret}) + "\n")
    meta = {"task": "Walker2d-v5", "seconds": 200.0, "seeds": [1], "gpu": "H200", "date": "2026-11-27", "command": "c"}
    rows = [{"label": f"num_envs={n}", "gymnasium_return": 5000.0,
             "runs": [{"seed": 1, "run_dir": f"/root/W/runs/Walker2d-v5-{k}", "gymnasium_return": 5000.0, "ratio": 1.0,
                       "samples_per_s": 6e5}]} for k, n in enumerate((8192, 16384))]
    path = tmp_path / "sweep-Walker2d-v5.json"
    path.write_text(json.dumps({"meta": meta, "rows": rows}))
    assert sw.main(["--times", str(path)]) == 0
    doc = json.loads(path.read_text())
    first, second = (r["runs"][0]["reaching"] for r in doc["rows"])
    assert first == {"target": {"time_s": 198.0, "samples": 25}, "half": {"time_s": 137.0, "samples": 15}}
    assert second == {"target": None, "half": None}  # half of 5007: 2503.5
    assert sw.minutes(doc["rows"][0]["runs"][0]) == "3.30" and sw.minutes(doc["rows"][1]["runs"][0]) == "not reached"
    os.remove(tmp_path / "runs" / "Walker2d-v5-1" / "metrics.jsonl")
    with pytest.raises(SystemExit, match="Walker2d-v5-1 has no metrics.jsonl; copy the sweep's runs/ folder"):
        sw.main(["--times", str(path)])


def test_train_modes_reads_rollout_captures_kept_json_medians_of_the_rounds_against_the_first_mode():
    """benchmarks/speed/rollout_capture.py's JSON ("step", "rollout", "off" per task) reads in train_modes' table under
    its mode names, with medians over the rounds (a failed run left out) and ratios to the whole rollout's graph."""
    from benchmarks.speed import train_modes as tm

    def run(ready, sps):
        return {"ready_s": ready, "samples_per_s": sps, "iterations": 100}

    doc = {"meta": {"gpu": "GPU"}, "runs": {"Ant-v5": {
        "step": [run(20.0, 2.6e5), run(22.0, 2.7e5), run(100.0, 2.5e5)],
        "rollout": [run(40.0, 2.7e5), run(44.0, 2.8e5), {"error": "exit 1: x"}], "off": [run(21.0, 2.0e5)]}}}
    (only,) = tm.from_capture_report(doc)
    lines = tm.tables(only).splitlines()
    # medians: rollout (its failed run left out) 42 s and 0.275 M; step 22 s and 0.26 M
    assert lines[4] == "| sequential | 2 of 3 | 42.0 s | 0.28 M | - | 1.00 | 1.000 | - | - | - | - |"
    assert lines[5] == "| step-graph | 3 of 3 | 22.0 s | 0.26 M | - | 0.52 | 0.945 | - | - | - | - |"
    assert lines[6] == "| no-graph | 1 of 1 | 21.0 s | 0.20 M | - | 0.50 | 0.727 | - | - | - | - |"


def test_train_modes_turns_the_first_mode_each_round_and_refuses_seeds_for_a_task_without_targets(capsys):
    from benchmarks.speed import train_modes as tm

    order = list(tm.rounds(["a", "b", "c"], 3))
    assert order == [(0, "a"), (0, "b"), (0, "c"), (1, "b"), (1, "c"), (1, "a"), (2, "c"), (2, "a"), (2, "b")]
    _, args = tm.parse(["--out", "x", "--task", "Hopper-v5"])
    assert args.seeds == [] and args.seconds == 0.0  # throughput only: Hopper has no target speeds
    _, args = tm.parse(["--out", "x", "--task", "Humanoid"])
    assert args.seeds == [0, 1, 2] and args.seconds == 240.0
    with pytest.raises(SystemExit):
        tm.parse(["--out", "x", "--task", "Hopper-v5", "--seeds", "0"])
    assert "--seeds 0: Hopper-v5 has no target speeds" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        tm.parse(["--out", "x", "--task", "Hopper-v5", "--throughput-seconds", "0"])
    assert "nothing to time" in capsys.readouterr().err


def test_suite_versions_plays_each_runs_last_policy_in_v4_and_names_the_term_that_moved(monkeypatch, tmp_path):
    """benchmarks/learning/suite_versions.py: the last kept policy of each run of a task that plays in v4 (Ant's runs
    left out), by ``warpgym eval --env-version 4``; the table's means over seeds and the term that moved most; a
    candidate preset's run (suite_learning --config) found in its own folder and given its own row."""
    from benchmarks.learning import suite_versions as sv

    from warpgym.cli import eval as eval_command

    calls = []

    def fake_eval(args):
        calls.append((os.path.relpath(args[0], tmp_path), args[args.index("--env-version") + 1]))
        seed = int(args[0].split("seed")[1][0])
        v5 = {"reward_dist": -3.0 - seed, "reward_ctrl": -0.8}
        v4 = {"reward_dist": -3.2 - seed, "reward_ctrl": -0.8}
        with open(args[args.index("--json") + 1], "w") as f:
            json.dump({"episodes": 30, "gymnasium_return": sum(v5.values()), "gymnasium_length": 50.0,
                       "v4_return": sum(v4.values()), "v4_length": 50.0, "gymnasium_terms": v5, "v4_terms": v4,
                       "v4_over_v5": 0.9 + 0.06 * seed}, f)

    monkeypatch.setattr(eval_command, "main", fake_eval)
    for task, seed, config in (("Reacher-v5", 0, []), ("Reacher-v5", 1, []), ("Ant-v5", 0, []),
                               ("Reacher-v5", 0, ["entropy_coef=0.01"])):
        kept = [{"mark_s": m, "checkpoint": f"checkpoint-{i}.pt"} for i, m in enumerate((60.0, 180.0))]
        stem = "-".join([task, *config, f"seed{seed}"])
        (tmp_path / f"{stem}.json").write_text(json.dumps({"run": {"task": task, "seed": seed, "kept": kept,
                                                                   "config": config}}))
        os.makedirs(tmp_path / "runs" / stem)
        (tmp_path / "runs" / stem / "checkpoint-1.pt").write_bytes(b"")
    rows = sv.score([str(tmp_path)], 10, "cpu")
    assert sorted(calls) == sorted((os.path.join("runs", stem, "checkpoint-1.pt"), "4") for stem in (
        "Reacher-v5-seed0", "Reacher-v5-seed1", "Reacher-v5-entropy_coef=0.01-seed0"))
    text = sv.table(rows)
    assert "| Reacher-v5 | 2 | 3 min | -4.3 | -4.5 | 0.930 | reward_dist -3.5 -> -3.7 | 50 / 50 | -2.6 (v2) |" in text
    assert "| Reacher-v5 (entropy_coef=0.01) | 1 | 3 min | -3.8 | -4.0 | 0.900 | reward_dist -3.0 -> -3.2 | 50 / 50 | " \
           "-2.6 (v2) |" in text
    os.remove(tmp_path / "runs" / "Reacher-v5-seed1" / "checkpoint-1.pt")
    with pytest.raises(SystemExit, match="its last policy .*checkpoint-1.pt is not there"):
        sv.score([str(tmp_path)], 10, "cpu")


def test_suite_versions_plays_again_only_what_changed(monkeypatch, tmp_path):
    """A policy's .v4.json from an earlier run is read, not played again, where it is newer than the checkpoint
    and played the same episodes from the same reset seeds; a newer checkpoint or other episodes play anew."""
    from benchmarks.learning import suite_versions as sv

    from warpgym.cli import eval as eval_command

    calls = []

    def fake_eval(args):
        calls.append(args[args.index("--episodes") + 1])
        episodes = int(args[args.index("--episodes") + 1])
        with open(args[args.index("--json") + 1], "w") as f:
            json.dump({"episodes": 3 * episodes, "gymnasium_return": -4.0, "gymnasium_length": 50.0,
                       "v4_return": -4.2, "v4_length": 50.0, "gymnasium_terms": {}, "v4_terms": {},
                       "v4_over_v5": 1.05, "v4_per_seed": [{"seed": s} for s in sv.SEEDS]}, f)

    monkeypatch.setattr(eval_command, "main", fake_eval)
    kept = [{"mark_s": 180.0, "checkpoint": "checkpoint-9.pt"}]
    (tmp_path / "Reacher-v5-seed0.json").write_text(json.dumps({"run": {"task": "Reacher-v5", "seed": 0,
                                                                         "kept": kept}}))
    ckpt = tmp_path / "runs" / "Reacher-v5-seed0" / "checkpoint-9.pt"
    os.makedirs(ckpt.parent)
    ckpt.write_bytes(b"")
    os.utime(ckpt, (1000, 1000))
    first = sv.score([str(tmp_path)], 10, "cpu")
    assert calls == ["10"] and sv.score([str(tmp_path)], 10, "cpu") == first and calls == ["10"]
    sv.score([str(tmp_path)], 5, "cpu")  # other episodes: played again
    assert calls == ["10", "5"]
    later = os.path.getmtime(str(ckpt) + ".v4.json") + 60
    os.utime(ckpt, (later, later))  # a checkpoint newer than its .v4.json (a run made again in the same folder)
    sv.score([str(tmp_path)], 5, "cpu")
    assert calls == ["10", "5", "5"]


def test_suite_learning_judges_the_minutes_to_the_figure_by_gymnasiums_scores_at_the_marks():
    """A seed is at its figure by a mark where the policy kept there scored it in Gymnasium's env, whatever the
    training's own evaluations said; a row is within 3 minutes only if every seed's policy was by the 3-minute mark,
    and a negative figure (a cost) is passed from below."""
    from benchmarks.learning import suite_learning as sl

    def run(task, seed, scores):
        marks = list(sl.marks_of(task, 1.0))
        return {"task": task, "seed": seed, "marks_s": marks, "reference": sl.REFERENCE[task], "samples": 1e6,
                "samples_per_s": 1e5, "evals": [{"time_s": 70.0, "samples": 1e6, "eval/return": 9e9}],  # training evals say 1.2 for all
                "scored": [{"mark_s": m, "gymnasium_return": v, "gymnasium_over_warpgym": 1.0}
                           for m, v in zip(marks, scores)]}

    walker = [run("Walker2d-v5", 0, [4000, 5100, 5200, 6000, 6500]), run("Walker2d-v5", 1, [3000, 4000, 5006.9, 5100, 6000])]
    assert sl.first_marks_at(walker, 5007.0) == [120.0, 300.0] and sl.marks_at(walker, 5007.0) == "2, 5"
    pusher = [run("Pusher-v5", s, [-45.0, -42.6, -40.0]) for s in (0, 1)]
    swimmer = [run("Swimmer-v5", 0, [10.0, 20.0, 30.0, 40.0, 44.0])]
    assert sl.marks_at(swimmer, 44.4) == "not by 10"
    assert sl.within(walker + pusher + swimmer, 180.0) == ["Pusher-v5"]
    walker[1]["scored"][2]["gymnasium_return"] = 5007.0
    assert sl.within(walker + pusher + swimmer, 180.0) == ["Pusher-v5", "Walker2d-v5"]
    assert sl.within(walker + pusher, 120.0) == ["Pusher-v5"]
    row = next(line for line in sl.table(walker).splitlines() if line.startswith("| Walker2d-v5"))
    assert "| 1.2, 1.2 (1.2, 1.2) | 2, 3 |" in row


def test_the_published_suite_tables_are_what_their_scripts_print_from_the_committed_runs(capsys):
    """docs/benchmarks.md's learning table (warpgym's and SB3's, and the candidates' rows) and its v4-beside-v5 table,
    row for row, as ``suite_learning.py --report`` and ``suite_versions.py --report`` print them from docs/bench: a
    row whose JSON changed without the page (or the other way round) fails here."""
    from benchmarks.learning import suite_learning as sl
    from benchmarks.learning import suite_versions as sv

    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    page = set(published(root).splitlines())
    bench = os.path.join(root, "docs", "bench")
    assert sl.report([os.path.join(bench, "suite_learning"), os.path.join(bench, "suite_sb3")]) == 0
    assert sv.main(["--report", os.path.join(bench, "suite_versions.json")]) == 0
    out = capsys.readouterr().out
    readme_part = out.split("The README's table:")[1].split("\n\n")[1]
    rows = [line for line in out.replace(readme_part, "").splitlines() if line.startswith("| ") and "---" not in line]
    assert len(rows) >= 11 + 5 + 7 + 3  # eleven tasks, SB3's five, seven in v4, the three header lines
    assert [r for r in rows if r not in page] == []
    with open(os.path.join(root, "README.md")) as f:
        readme = set(f.read().splitlines())
    readme_rows = [line for line in readme_part.splitlines() if line.startswith("| ") and "---" not in line]
    assert len(readme_rows) == 1 + 11 and [r for r in readme_rows if r not in readme] == []
    # the table's note on the cards, as printed: every row it marks named (it once left out Walker2d-v5)
    note = out.split("The README's table:")[1].split("\n\n")[2].strip()
    marked = [r[2:].split(" ‡")[0] for r in readme_rows if "‡" in r]
    assert note.startswith("‡") and note in readme and marked and all(
        re.search(rf"[:,] {re.escape(task)}\b", note) for task in marked)
    # a candidate's row, shown (indented) where the page says why it is not the preset
    assert sl.report([os.path.join(bench, "suite_learning", "candidates")]) == 0
    out = capsys.readouterr().out.split("The README's table:")[0]
    candidates = [line for line in out.splitlines() if line.startswith(("| Swimmer-v5 (", "| Walker2d-v5 ("))]
    assert len(candidates) == 3 and [c for c in candidates if c not in {line.strip() for line in page}] == []
    # Walker2d-v5's network beside the preset of its day, paired on one host
    assert sl.report([os.path.join(bench, "suite_learning", "walker2d_paired")]) == 0
    out = capsys.readouterr().out.split("The README's table:")[0]
    paired = [line for line in out.splitlines() if line.startswith("| Walker2d-v5")]
    assert len(paired) == 2 and [p for p in paired if p not in page] == []


@pytest.mark.parametrize("folder, task, settings", [("multi_gpu", "Ant", 9), ("multi_gpu", "Humanoid", 3),
                                                    ("multi_gpu/kl_target", "Humanoid", 4),
                                                    ("multi_gpu/grow_kl", "Ant", 3), ("multi_gpu/grow_kl", "Humanoid", 3),
                                                    ("multi_gpu/suite", "Humanoid-v5", 4), ("multi_gpu/suite", "Ant-v5", 4)])
def test_the_published_multi_gpu_table_is_what_scaling_prints_from_the_committed_runs(tmp_path, capsys, folder, task,
                                                                                    settings):
    """docs/benchmarks.md's time-to-target tables for several GPUs, row for row, as ``benchmarks/multi_gpu/scaling.py
    --report`` prints them from the runs' metrics committed in docs/bench/multi_gpu (read again, not from the JSON's
    numbers): a number changed on the page or in the reading of the runs fails here. The first folder holds both
    tasks; kl_target the Humanoid's KL-target runs of another lease; grow_kl both tasks under the default on 1, 2 and 4
    GPUs, a third lease; suite Gymnasium's Humanoid-v5 and Ant-v5 on 1, 2 and 4 GPUs, a fourth and a fifth."""
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    from benchmarks.multi_gpu import scaling

    shutil.copytree(os.path.join(root, "docs", "bench", *folder.split("/")), tmp_path / "mg",
                    ignore=shutil.ignore_patterns("kl_target", "grow_kl", "nodes", "suite"))
    assert scaling.main(["--report", str(tmp_path / "mg"), "--task", task]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{task}: ")
    rows = [line for line in out.splitlines() if line.startswith("| ") and "---" not in line]
    page = set(published(root).splitlines())
    assert len(rows) == 1 + settings  # the header, one GPU and the multi-GPU settings
    assert [r for r in rows if r not in page] == []
    if folder in ("multi_gpu/grow_kl", "multi_gpu/suite"):  # the KL rule's ranges the page quotes, as printed
        rule = [line for line in out.splitlines() if line.startswith("The KL rule, each run's median")]
        assert len(rule) == 1 and rule[0] in {line.strip() for line in page}
    if folder == "multi_gpu/suite":  # and what each setting had learnt by one GPU's median iteration
        by = [line for line in out.splitlines() if line.startswith("By iteration ")]
        assert len(by) == 1 and by[0] in {line.strip() for line in page}


def test_a_packed_outputs_report_reads_its_runs_outside_it_and_leaves_it_as_it_was(tmp_path, capsys, monkeypatch):
    """The docs' checks report committed folders, two at once under pytest-xdist: a report unpacks into a folder of
    its own, not into the output, and removes it after."""
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    from benchmarks.multi_gpu import scaling

    out = tmp_path / "grow_kl"
    shutil.copytree(os.path.join(root, "docs", "bench", "multi_gpu", "grow_kl"), out)
    before = sorted(os.listdir(out))
    seen = []
    gather = scaling.gather_runs
    monkeypatch.setattr(scaling, "gather_runs", lambda folder, doc, runs_dir: (seen.append(runs_dir),
                                                                             gather(folder, doc, runs_dir)))
    assert scaling.main(["--report", str(out), "--task", "Humanoid"]) == 0
    assert capsys.readouterr().out.startswith("Humanoid: ")
    assert len(seen) == 1 and not os.path.abspath(seen[0]).startswith(str(out))
    assert not os.path.exists(os.path.dirname(seen[0]))
    assert sorted(os.listdir(out)) == before


def test_a_folder_of_several_tasks_asks_which(tmp_path):
    from benchmarks.multi_gpu import scaling

    for task in ("Ant", "Humanoid"):
        (tmp_path / f"scaling_{task}.json").write_text("{}")
    assert scaling.task_json(str(tmp_path), "Humanoid").endswith("scaling_Humanoid.json")
    with pytest.raises(SystemExit, match="Ant, Humanoid but not Hopper-v5: name one with --task"):
        scaling.task_json(str(tmp_path), "Hopper-v5")


@pytest.mark.parametrize("module, args, count", [
    ("benchmarks.multi_gpu.nodes", ["docs/bench/multi_gpu/nodes/nodes-1.json", "docs/bench/multi_gpu/nodes/nodes-2.json"], 9),
    ("benchmarks.multi_gpu.nodes", ["docs/bench/multi_gpu/nodes/nodes-4.json"], 5),
    ("benchmarks.reliability.exits", ["docs/bench/gpu_exits.json"], 8),
    ("benchmarks.reliability.exits", ["docs/bench/reliability/gpu_exits_h200.json"], 4),
    ("benchmarks.reliability.exits", ["docs/bench/reliability/gpu_exits_h200x4_a.json",
                                      "docs/bench/reliability/gpu_exits_h200x4_b.json"], 29),
    ("benchmarks.learning.learners", ["docs/bench/rllib/h200_rllib_vs_warpgym_1gpu.json",
                                               "docs/bench/rllib/h200_rllib_8runners_1gpu.json",
                                               "docs/bench/rllib/h200_rllib_vs_warpgym_2gpu_warpgym.json",
                                               "docs/bench/rllib/h200_rllib_vs_warpgym_2gpu_rllib.json",
                                               "docs/bench/rllib/h200_rllib_vs_warpgym_2gpu_rllib_humanoid.json",
                                               "docs/bench/rllib/h200_rllib_vs_warpgym_4gpu_ant.json",
                                               "docs/bench/rllib/h200_rllib_vs_warpgym_4gpu_humanoid.json"], 15),
    ("benchmarks.learning.suite_sweep", [f"docs/bench/suite_sweep/InvertedDoublePendulum-v5-180s-h200x4/idp-{arm}.json"
                                         for arm in ("u0-s0", "u0-s1", "u0-s2", "u0-s3", "u1e7", "nofalse")], 4),
    ("benchmarks.learning.suite_sweep", ["docs/bench/suite_sweep/Hopper-v5-300s-h200x4/sweep-gamma.json"], 3),
    ("benchmarks.learning.suite_sweep", ["docs/bench/suite_sweep/HalfCheetah-v5-600s-h200x4/sweep-entropy-net.json"], 5),
    ("benchmarks.learning.suite_sweep", ["docs/bench/suite_sweep/Swimmer-v5-300s-h200x4/sweep-gamma-horizon.json"], 5),
    ("benchmarks.learning.suite_sweep", ["docs/bench/suite_sweep/InvertedPendulum-v5-180s-h200x4/sweep-kl.json"], 3),
    ("benchmarks.learning.suite_sweep", ["docs/bench/suite_sweep/Walker2d-v5-200s-h200x2/sweep-envs.json"], 3),
    ("benchmarks.learning.suite_sweep", ["docs/bench/suite_sweep/Walker2d-v5-200s-h200x4/sweep-eval-background.json"], 3),
    ("benchmarks.learning.suite_sweep", ["docs/bench/suite_sweep/Walker2d-v5-200s-h200x2/sweep-eval-woven-seeds0-3.json"], 3),
    ("benchmarks.learning.suite_sweep", ["docs/bench/suite_sweep/Walker2d-v5-200s-h200x2/sweep-eval-woven-seeds4-7.json"], 2),
    ("benchmarks.learning.suite_sweep", [f"docs/bench/suite_sweep/Walker2d-v5-200s-h200x2/sweep-{arm}.json"
                                         for arm in ("minibatch", "kl")], 4),
    ("benchmarks.learning.suite_sweep", [f"docs/bench/suite_sweep/Walker2d-v5-200s-h200x2/sweep-{arm}.json"
                                         for arm in ("minibatch-seeds4-7", "kl-seeds4-5", "kl-seeds6-7")], 3),
    ("benchmarks.learning.suite_sweep", [f"docs/bench/suite_sweep/Walker2d-v5-200s-h200x4/sweep-eval-gap-20-seeds{s}.json"
                                         for s in ("0-3", "4-7")], 2),
    ("benchmarks.learning.suite_sweep", [f"docs/bench/suite_sweep/Walker2d-v5-200s-h200x4/sweep-net-seeds{s}.json"
                                         for s in ("0-7", "8-15")], 2),
    ("benchmarks.speed.background_overlap", [f"docs/bench/background_eval/walker2d_h200_{name}.json"
                                             for name in ("queues8", "queues32", "host_replays")], 6),
    ("benchmarks.speed.background_overlap", [f"docs/bench/background_eval/walker2d_h200x2_interleaved{name}.json"
                                             for name in ("", "_r5")], 6),
    ("benchmarks.learning.reacher_planner", ["docs/bench/reacher_planner.json"], 4),
    ("benchmarks.learning.reacher_planner", ["docs/bench/reacher_planner_25knots.json"], 3)])
def test_the_published_nodes_exits_and_planner_tables_are_what_their_scripts_print(capsys, module, args, count):
    """The two-node, GPU exits, RLlib comparison, sweeps' and Reacher planner tables in docs/benchmarks.md, row for row, from
    the committed JSON (the planner's table sits in a list item, indented); the exits' totals over every GPU lease
    as the page states them."""
    import importlib

    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    script = importlib.import_module(module)
    assert script.main(["--report", *[os.path.join(root, a) for a in args]]) == 0
    out = capsys.readouterr().out
    rows = [line for line in out.splitlines() if line.startswith("| ") and "---" not in line]
    page = [line.strip() for line in published(root).splitlines()]
    assert len(rows) == count and [r for r in rows if r not in page] == []
    if module.endswith("exits") and len(args) == 2:  # the page's totals: these two and the two earlier leases' files
        assert script.main(["--report", *[os.path.join(root, a) for a in ("docs/bench/gpu_exits.json",
                                                                          "docs/bench/reliability/gpu_exits_h200.json",
                                                                          *args)]]) == 0
        totals = capsys.readouterr().out.strip().splitlines()[-4:]
        assert len(totals) == 4 and [t for t in totals if t not in page] == []
    if module.endswith("nodes"):  # the verdict the page states (2 nodes of 1 H100; 2 nodes of 2 H200s)
        verdict = {"nodes-1.json": "1.003 (median of 3: 1.002, 1.003, 1.006)",
                   "nodes-4.json": "0.999 (median of 2: 0.998, 1.000)"}[os.path.basename(args[0])]
        assert f"2 nodes / 1 node: {verdict}; target within 5%: met" in out


def test_exits_report_joins_runs_numbering_rows_in_turn_and_counting_all(capsys):
    """Two exits.json (two GPU pairs of one host, or two days) in one table: rows numbered on, every machine and
    date in the heading, and the counts over both files."""
    from benchmarks.reliability import exits

    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    files = [os.path.join(root, "docs", "bench", "gpu_exits.json"),
             os.path.join(root, "docs", "bench", "reliability", "gpu_exits_h200.json")]
    assert exits.main(["--report", *files]) == 0
    out = capsys.readouterr().out
    assert out.splitlines()[0] == ("2 processes on NVIDIA H100 80GB HBM3, 2026-11-26; 2 processes on NVIDIA H200, "
                                   "2026-11-26 (2 runs of the script)")
    assert "| 10 | killed-rank | Ant |" in out and "| 11 |" not in out
    assert "killed-rank: 2 of 2 stopped every process" in out and "4 of 4 finished runs" in out


def test_the_comparison_gives_warpgym_as_many_robots_per_gpu_as_rllibs_runners_in_every_mode():
    import argparse

    args = argparse.Namespace(hparams="preset", num_envs=4096, seconds=60.0, seed=0, device=None,
                              rllib_env_runners=None, warpgym_multi_gpu="grow-batch")

    def flag(cmd, name):
        return cmd[cmd.index(name) + 1]

    rllib = cmp.command("rllib", "Ant", 2, args, "/x/r")
    assert flag(rllib, "--num-envs") == "4096" and flag(rllib, "--gpus") == "2"  # two runners of 4096
    ours = cmp.command("warpgym", "Ant", 2, args, "/x/w")
    assert (flag(ours, "--num-envs"), flag(ours, "--multi-gpu")) == ("4096", "grow-batch")
    args.warpgym_multi_gpu = "split"  # split's --num-envs is the run's total: 4096 on each of 2 GPUs
    ours = cmp.command("warpgym", "Ant", 2, args, "/x/w")
    assert (flag(ours, "--num-envs"), flag(ours, "--multi-gpu")) == ("8192", "split")
    assert "--multi-gpu" not in cmp.command("warpgym", "Ant", 1, args, "/x/w")
    # an adapter's learner keeps its own settings: train-with takes the hyperparameters for rllib only
    skrl = cmp.command("skrl", "Ant", 1, args, "/x/s")
    assert skrl[3:5] == ["train-with", "skrl"] and flag(skrl, "--num-envs") == "4096" and "--batch-size=32768" not in skrl


def test_the_learners_report_reads_the_kept_adapter_runs_beside_rllibs():
    """The kept learners.json of the adapters (one GPU, their defaults) reads as comparison rows: one per learner,
    each named by its adapter, the first iteration's time kept."""
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    doc = cmp.merged_reports([os.path.join(root, "docs", "bench", "learners", "h100_learners_ant.json")])
    text = cmp.table(doc)
    rows = [line for line in text.splitlines() if line.startswith("| Ant |")]
    assert len(rows) == 5 and any("skrl (`SkrlVecEnv`), 1 GPU" in r for r in rows)
    assert all(r.split("|")[4].strip().endswith(" s") for r in rows)  # the first iteration's time


def test_suite_sweep_called_again_sweeps_only_the_settings_not_done(monkeypatch, tmp_path):
    """On one GPU a sweep writes its JSON after each setting: the same command in a later call (the first stopped by
    a call's time limit) keeps those rows and sweeps the rest; a JSON of another budget is refused, not mixed."""
    from benchmarks.learning import suite_sweep as sw

    argv = ["--out", str(tmp_path), "--task", "Hopper-v5", "--grid", "gamma=0.99,0.999", "--seeds", "0",
            "--seconds", "60", "--device", "cpu", "--no-warm-up"]
    swept = []
    monkeypatch.setattr(sw, "run_combo", lambda task, combo, *a: swept.append(combo) or {
        "combo": combo, "label": sw.label_of(combo), "runs": [], "gymnasium_return": 2.0})
    assert sw.main(argv) == 0 and swept == [{"gamma": "0.99"}, {"gamma": "0.999"}]
    doc = json.loads((tmp_path / "sweep-Hopper-v5.json").read_text())
    doc["rows"] = doc["rows"][:1]  # as a call stopped after the first setting left it
    (tmp_path / "sweep-Hopper-v5.json").write_text(json.dumps(doc))
    swept.clear()
    assert sw.main(argv) == 0 and swept == [{"gamma": "0.999"}]
    assert [r["label"] for r in json.loads((tmp_path / "sweep-Hopper-v5.json").read_text())["rows"]] == [
        "gamma=0.99", "gamma=0.999"]
    with pytest.raises(SystemExit, match="holds a sweep with other task, seconds, seeds, scoring"):
        sw.main([*argv[:-5], "--seconds", "90", "--device", "cpu", "--no-warm-up"])


def test_suite_sweep_stopped_by_a_call_limit_waits_for_its_parts_and_starts_no_more(monkeypatch, tmp_path):
    """SIGTERM (a call's `timeout`, to the process group) during a ``--gpus`` sweep: the part running saves and ends,
    the sweep waits for it, starts no other part, joins nothing, and exits 143; the next call goes on from there."""
    import argparse
    import signal
    import subprocess
    import time

    from benchmarks.learning import suite_sweep as sw

    started, before = [], signal.getsignal(signal.SIGTERM)

    def fake_child(cmd, **kw):
        started.append(cmd[cmd.index("--out") + 1])
        os.kill(os.getpid(), signal.SIGTERM)  # arrives while this part runs; the part saves (a moment) and ends
        time.sleep(0.5)
        return subprocess.CompletedProcess(cmd, 143)

    monkeypatch.setattr(sw.subprocess, "run", fake_child)
    monkeypatch.delenv("CUDA_VISIBLE_DEVICES", raising=False)
    args = argparse.Namespace(gpus=1, seeds=[0], out=str(tmp_path), task="Hopper-v5")
    with pytest.raises(SystemExit) as stop:
        sw.spread(args, {"gamma": ["0.99", "0.999"]}, ["--task", "Hopper-v5", "--grid", "gamma=0.99,0.999"])
    assert stop.value.code == 143 and len(started) == 1 and started[0].endswith("000")
    assert signal.getsignal(signal.SIGTERM) is before and not (tmp_path / "sweep-Hopper-v5.json").exists()


def test_suite_learning_report_of_runs_not_scored_yet_says_so(tmp_path, capsys):
    """``--no-score`` keeps the GPU for training and leaves the scoring to ``--score OUT``: the report at the end of
    such a call (and any before the scoring) shows the runs unscored, not a traceback."""
    from benchmarks.learning import suite_learning as sl

    marks = list(sl.marks_of("Hopper-v5", 1.0))
    run = {"task": "Hopper-v5", "seed": 0, "budget_s": marks[-1], "marks_s": marks, "samples": 2.4e8, "num_envs": 4096,
           "samples_per_s": 4.0e5, "reference": sl.REFERENCE["Hopper-v5"], "device": "cuda:0", "scored": [],
           "curve": [[30.0, 131072, 10.0]], "first_eval_reaching": {"target": None, "half": {"time_s": 180.0}},
           "evals": [{"time_s": 180.0, "samples": 7e7, "eval/return": 1800.0}], "rollout_graph": "step"}
    (tmp_path / "Hopper-v5-seed0.json").write_text(json.dumps({"meta": {"gpu": "H100", "scale": 1.0, "date": "d",
                                                                        "command": "x"}, "run": run}))
    assert sl.report([str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "| Hopper-v5 | 1 | 1 min: -; 2 min: -; 3 min: -; 5 min: -; 10 min: - |" in out and "| not scored |" in out
    assert "| Hopper-v5 | not scored yet (`--score OUT`) | 3542.2 (Tianshou, v3) | not reached |" in out


@pytest.mark.parametrize("seed", [1, 2])
def test_the_published_scores_of_the_4_gpu_humanoid_v5_checkpoints_are_their_eval_json(seed):
    """docs/benchmarks.md's `warpgym eval` line for each torchrun checkpoint (split-horizon, 4 H200s) holds the numbers
    of the JSON that `warpgym eval --json` wrote: a changed number on either side fails here."""
    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    path = os.path.join(root, "docs", "bench", "multi_gpu", "suite", f"eval_humanoid-v5_gpu4-split-horizon-seed{seed}.json")
    with open(path) as f:
        scored = json.load(f)
    page = " ".join(published(root).split())  # the page's lines wrap
    assert scored["task"] == "Humanoid-v5" and scored["episodes"] == 30 and scored["same_starts"]
    said = (f"Seed {seed}'s" if seed == 1 else f"seed {seed}'s") + f" (iteration {scored['iteration']})"
    assert said in page
    assert f"{scored['gymnasium_return']:.1f} ± {scored['gymnasium_return_std']:.1f}" in page
    assert f"{scored['gymnasium_over_warpgym']:.3f}" in page and f"{scored['warpgym_return']:.1f}" in page
    assert min(scored["gymnasium_lengths"]) == 1000  # "every Gymnasium episode lasted its 1000 steps"


def test_by_iteration_line_sets_the_settings_side_by_side_at_one_gpus_median_iteration():
    """What each setting had learnt by one GPU's median iterations to the target: a run that reached it sooner counts
    with its hit (not the closing evaluation after it), a run cut before that iteration is left out, and a setting
    with none left says so."""
    from benchmarks.multi_gpu import scaling

    def run(gpus, mode, evals, hit=None, iterations=None):
        return {"gpus": gpus, "mode": mode, "iterations": iterations or evals[-1][0], "by_iteration": evals,
                "to_target": {"100": {"iteration": hit} if hit else None}}

    doc = {"targets": {"key": "eval/return", "values": [100.0]}}
    grouped = {(1, "-"): [run(1, "-", [[10, 50, 0.9], [20, 80, 0.8], [30, 100, 0.7]], hit=30),
                          run(1, "-", [[10, 60, 0.9], [20, 100, 0.8], [21, 90, 0.8]], hit=20),
                          run(1, "-", [[10, 40, 0.9], [20, 70, 0.8], [40, 100, 0.6]], hit=40)],
               (2, "split"): [run(2, "split", [[12, 55, 0.5], [24, 95, 0.4]], iterations=40),
                              run(2, "split", [[8, 30, 0.5]], iterations=9)],  # cut at 9: left out
               (4, "grow"): [run(4, "grow", [[5, 20, 0.9]], iterations=6)]}
    lines = [{"gpus": g, "mode": m} for g, m in grouped]
    assert scaling.common_iteration(100.0, grouped) == 30
    out = scaling.by_iteration_line(doc, lines, 100.0, grouped)
    assert out.startswith("By iteration 30 (one GPU's median iterations to eval/return 100)")
    # the 1-GPU runs: 100 at 30 (its hit), 100 at 20 (its hit, not the 90 after it), 70 at 20
    assert "1 GPU -: 70-100 at iterations 20-30, noise std 0.70-0.80 (3 of 3 runs)" in out
    assert "2 GPUs split: 95.00 at iterations 24, noise std 0.40 (1 of 2 runs)" in out
    assert "4 GPUs grow: - (0 of 1 runs got that far)" in out
    assert scaling.by_iteration_line(doc, lines, 100.0, {**grouped, (1, "-"): grouped[(2, "split")]}) == ""


def test_background_overlap_times_the_chunk_beside_the_iteration_and_refuses_empty_timings(tmp_path, capsys):
    """benchmarks/speed/background_overlap.py on the CPU: the evaluation's chunks and woven steps run eagerly
    (nothing to capture), every timing is there and positive, the JSON reads back into the same table; zero iterations is one line. A
    table with an interleaved run beside older ones gives those "-" there."""
    from benchmarks.speed import background_overlap as bo

    out = tmp_path / "smoke.json"
    assert bo.main(["--task", "Hopper-v5", "--num-envs", "16", "--eval-envs", "4", "--iterations", "1",
                    "--repeats", "1", "--device", "cpu", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["captured"] is False and doc["host_replay_s"] == {} and doc["steps_per_chunk"] == 32
    # the runner's woven iterations: eager on a CPU, its rollout's steps each with one evaluation step beside
    assert doc["horizon"] == 32 and len(doc["interleaved_s"]) == 1 and doc["interleaved_s"][0] > 0
    assert all(v > 0 for v in doc["median_s"].values()) and doc["launch_idle_s"] > 0
    printed = capsys.readouterr().out
    assert bo.main(["--report", str(out)]) == 0
    row = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| Hopper-v5")]
    assert len(row) == 1 and "(eager)" in row[0] and row[0] in printed
    older = {k: v for k, v in doc.items() if k not in ("interleaved_s", "overlap_interleaved", "horizon")}
    woven = {**doc, "interleaved_s": [0.4, 0.3], "overlap_interleaved": 0.75}
    rows = [line for line in bo.table([older, woven]).splitlines() if line.startswith("| Hopper-v5")]
    assert rows[0].endswith("| - | - |") and rows[1].endswith("| 350.0 ms | 0.75 |")
    with pytest.raises(SystemExit) as stop:
        bo.main(["--iterations", "0"])
    assert stop.value.code == 2 and "--iterations 0" in capsys.readouterr().err


def test_the_suite_gif_caption_gives_the_drawn_policies_scores_and_cards_from_the_tables_json():
    """The GIFs of Gymnasium's tasks (docs/tasks.md, at the head of the suite's section) are seed 0's 10-minute policies
    of the learning table: the caption's scores and each alt text's card are those of the table's JSON, so a row made
    again (a preset changed, the row promoted, the GIF redrawn) cannot leave the superseded row's score or card."""
    import re

    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    with open(os.path.join(root, "docs", "tasks.md")) as f:
        readme = f.read()
    caption = re.search(r"Gymnasium's ((?:[\w-]+-v5, )+[\w-]+-v5 and [\w-]+-v5) after 10 minutes, which score "
                        r"([\d, and-]+) in `gymnasium.make`'s env \(seed 0\)", " ".join(readme.split()))
    assert caption, "the GIF caption of docs/tasks.md's suite section moved or changed its form"
    tasks = re.split(r", | and ", caption.group(1))
    scores = [int(v) for v in re.split(r", | and ", caption.group(2))]
    assert len(tasks) == len(scores) == 7
    for task, score in zip(tasks, scores):
        with open(os.path.join(root, "docs", "bench", "suite_learning", f"{task}-seed0.json")) as f:
            doc = json.load(f)
        last = max(doc["run"]["scored"], key=lambda s: s["mark_s"])
        assert round(last["gymnasium_return"]) == score, task
        card = "H200" if "H200" in doc["meta"]["gpu"] else "H100"
        assert f"alt=\"Gymnasium's {task} trained for 10 minutes on one {card}\"" in readme, task


def test_the_physics_tables_are_what_fidelity_prints_from_todays_defaults_runs(capsys):
    """docs/benchmarks.md's "Physics at convergence" table and the log's table of its training runs, row for row, as
    ``fidelity.py --report`` prints them from the committed runs of today's defaults (the page's table was once
    edited by hand)."""
    from benchmarks.physics import fidelity

    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    runs = ["h100_ant_seed0_600s", "h100_ant_seed1_600s", "h100_ant_8192envs_seed0_300s",
            "h100_humanoid_3x8_motor25_armature0.1_seed0_600s", "h100_humanoid_3x8_motor25_armature0.1_seed1_600s"]
    paths = [os.path.join(root, "docs", "bench", "fidelity", f"{r}.json") for r in runs]

    def rows(*flags):
        assert fidelity.main(["--report", *paths, *flags]) == 0
        return [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ") and "---" not in line]

    page = set()
    for name in ("benchmarks.md", "history.md"):  # the policies' table on the page, their training runs' in the log
        with open(os.path.join(root, "docs", name)) as f:
            page |= set(f.read().splitlines())
    shown, every = rows("--marks", "end"), rows()
    assert len(shown) == 2 + 5 + 5 and [r for r in shown if r not in page] == []
    # the page leaves out the policies kept at 60, 120 and 300 s (the log has them), and only those
    assert len(every) == 2 + 19 + 5 and all(any(f" | {m} s (it " in r for m in (60, 120, 300))
                                            for r in set(every) - set(shown))
    with pytest.raises(SystemExit):
        fidelity.main(["--report", *paths, "--marks", "two"])
    assert "--marks two: each is a number of seconds or 'end'" in capsys.readouterr().err


def test_the_suite_speed_table_is_what_suite_speed_prints_from_the_committed_runs(capsys):
    """docs/benchmarks.md's suite speed table, header and rows, as ``suite_speed.py --report`` prints it (the page's
    header once lost its last three columns to a hand edit)."""
    from benchmarks.speed import suite_speed

    root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    bench = os.path.join(root, "docs", "bench")
    suite_speed.main(["--report", os.path.join(bench, "suite_speed_h100_same_states.json"),
                      os.path.join(bench, "suite_speed_h100_cpu.json")])
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("|")]
    with open(os.path.join(root, "docs", "benchmarks.md")) as f:
        page = set(f.read().splitlines())
    assert len(rows) == 2 + 11 and [r for r in rows if r not in page] == []
