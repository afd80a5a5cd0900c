"""scripts/train.py end to end on the CPU: a short Ant run writes everything, and a resume continues it."""

import json
import os

import pytest
import torch

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402
from warpgym.cli import eval as eval_cmd  # noqa: E402
from warpgym.cli import play, run_setup, sim2sim, train  # noqa: E402

from agents.checkpoint import load  # noqa: E402
from agents.logger import read_metrics  # noqa: E402


def test_short_cpu_run_writes_logs_checkpoint_plots_resumes_and_plays(tmp_path, capsys):
    run = str(tmp_path / "ant")
    common = ["--horizon-len", "8", "--save-gap", "2", "--eval-gap", "0", "--eval-envs", "2",
              "--episode-length", "40", "--save-at", "0"]
    assert train.main(["--task", "Ant", "--device", "cpu", "--num-envs", "8", "--max-iterations", "3",
                       "--run-dir", run, *common]) == 0
    last = capsys.readouterr().out.strip().splitlines()[-1]  # a sentence for a person, the next command in it
    assert last.startswith("Trained Ant for 3 iterations (0.2 k samples") and "best evaluation returned" in last
    assert f"Next: warpgym eval {run} scores it in native MuJoCo; warpgym play {run} --gif ant.gif" in last
    for name in ("config.json", "metrics.jsonl", "metrics.csv", "checkpoint.pt", "summary.json",
                 "reward_vs_time.png", "reward_vs_samples.png"):
        assert os.path.getsize(os.path.join(run, name)) > 0, name
    rows = read_metrics(run)
    assert [r["iteration"] for r in rows] == [1, 2, 3]
    assert all(r["samples"] == 64 * r["iteration"] for r in rows)
    assert all("eval/return" in r for r in rows) and rows[-1]["episodes"] >= 0
    assert load(os.path.join(run, "checkpoint.pt"), torch.device("cpu"))["iteration"] == 3
    saved = json.load(open(os.path.join(run, "config.json")))
    assert saved["num_envs"] == 8 and saved["minibatch_size"] == 32  # 8 envs x 8 steps, two mini-batches
    # the whole physics it trained with, so that later replays use it whatever the defaults become
    from warpgym.tasks.robots import ANT

    assert saved["env_args"]["substeps"] == ANT.substeps and saved["env_args"]["physics"] == ANT.physics.to_dict()
    # asked for the step capture (the default), a CPU run collects eagerly and its summary says so
    assert json.load(open(os.path.join(run, "summary.json")))["rollout_graph"] == "off"

    assert train.main(["--resume", run, "--max-iterations", "5", "--no-plots"]) == 0
    rows = read_metrics(run)
    assert [r["iteration"] for r in rows] == [1, 2, 3, 4, 5]
    assert rows[3]["time_s"] > rows[2]["time_s"]  # the wall-clock axis carries on across processes
    assert load(os.path.join(run, "checkpoint.pt"), torch.device("cpu"))["samples"] == 5 * 64
    # the resumed run's summary is the whole run's: its iterations, the mark kept by the first process, the resume
    summary = json.load(open(os.path.join(run, "summary.json")))
    assert summary["iterations"] == 5 and summary["first_iteration_time_s"] == rows[0]["time_s"]
    assert [(k["mark_s"], k["iteration"]) for k in summary["kept_checkpoints"]] == [(0.0, 1)]
    assert [r["iteration"] for r in summary["resumes"]] == [3] and 0 < summary["resumes"][0]["time_s"] < rows[3]["time_s"]

    # the deterministic policy of that run plays full 40-step episodes and reports return and speed
    assert play.main([run, "--device", "cpu", "--num-envs", "2", "--json", str(tmp_path / "play.json")]) == 0
    assert capsys.readouterr().out.strip().splitlines()[-1].startswith(f"Next: warpgym play {run} --gif ant.gif")
    result = json.loads((tmp_path / "play.json").read_text())
    assert result["iteration"] == 5 and result["episodes"] == 2
    assert 0 < result["eval/length"] <= 40 and result["eval/return"] != 0

    # ... and replays in warpgym and native MuJoCo at the training step and 2x finer
    out = str(tmp_path / "s2s.json")
    assert sim2sim.main([run, "--device", "cpu", "--envs", "2", "--native-copies", "2", "--steps", "30",
                         "--finer", "2", "--out", out]) == 0
    with open(out) as f:
        rows = json.load(f)["rows"]
    n = ANT.substeps
    assert [(r["simulator"], r["substeps"]) for r in rows] == [("warpgym", n), ("warpgym", 2 * n),
                                                              ("native MuJoCo", n), ("native MuJoCo", 2 * n)]
    assert rows[0]["speed_ratio"] == 1.0
    for r in rows:
        assert 0.0 <= r["no_foot_contact_share"] <= 1.0 and 0 <= r["longest_airborne_steps"] <= 30
        assert r["torso_height"] > 0.2 and r["robots"] == 2

    # warpgym eval scores a robot's policy where it is judged, native MuJoCo: sim2sim's replay, one episode of
    # the trained length (40 steps), episodes x seeds robots; Gymnasium's own flags are refused by name
    scored = str(tmp_path / "eval.json")
    assert eval_cmd.main([run, "--episodes", "2", "--seeds", "3", "--json", scored]) == 0
    with open(scored) as f:
        rows = json.load(f)["rows"]
    assert [r["simulator"] for r in rows] == ["warpgym", "warpgym", "native MuJoCo", "native MuJoCo"]
    assert rows[2]["robots"] == 2 and all(r["forward_speed"] == r["forward_speed"] for r in rows)
    capsys.readouterr()
    with pytest.raises(SystemExit) as refused:
        eval_cmd.main([run, "--nudge", "1e-6"])
    assert refused.value.code == 2 and "--nudge: Gymnasium's env only" in capsys.readouterr().err


def test_gait_meter_counts_flights_until_a_robot_ends():
    meter = sim2sim.GaitMeter(2, "test")
    z, vel = np.full(2, 0.5), np.zeros((2, 3))
    # robot 0: ground, 3 steps in the air, ground, 1 in the air; robot 1 flies 2 steps, then ends
    touching = [(True, False), (False, False), (False, True), (False, True), (True, True), (False, True)]
    ended = [(False, False), (False, True), (False, False), (False, False), (False, False), (False, False)]
    for step, (t, e) in enumerate(zip(touching, ended)):
        # each robot's speed so far; robot 1's after its end belongs to a new episode and must not count
        meter.add(np.array([1.0 + step, 2.0 if step < 2 else 9.0]), z, vel, np.array(t), np.array(e))
    r = meter.result(np.array([False, True]))
    # robot 0 is up 6 steps (4 airborne), robot 1 2 steps (2 airborne) before it ended
    assert r["no_foot_contact_share"] == 6 / 8
    assert r["longest_airborne_steps"] == np.median([3, 2])
    assert r["forward_speed"] == (6.0 + 2.0) / 2 and r["falls"] == 1


def test_play_prints_one_forward_speed_per_thing_measured_and_they_agree(tmp_path, capsys):
    """An episode cut short by --steps and the clip of that episode are the same travel over the same
    time: play.py must print the same forward speed for both (it once printed 0 for the first)."""
    pytest = __import__("pytest")
    pytest.importorskip("av")
    pytest.importorskip("PIL")
    run = str(tmp_path / "ant")
    assert train.main(["--task", "Ant", "--device", "cpu", "--num-envs", "8", "--max-iterations", "2",
                       "--horizon-len", "8", "--no-eval", "--no-plots", "--run-dir", run]) == 0
    capsys.readouterr()
    gif = str(tmp_path / "a.gif")
    assert play.main([run, "--device", "cpu", "--steps", "20", "--gif", gif, "--width", "160", "--height",
                      "120", "--gif-width", "160", "--json", str(tmp_path / "play.json")]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    result = json.loads((tmp_path / "play.json").read_text())
    speeds = [line for line in lines if "forward speed" in line]
    assert len(speeds) == 2, lines  # the episodes, then the clip
    assert result["eval/length"] == 20 and abs(result["eval/speed"]) > 1e-3
    assert abs(result["clip/forward_speed"] - result["eval/speed"]) <= 0.01 * abs(result["eval/speed"])
    assert os.path.getsize(gif) > 0


def test_fidelity_replays_a_probe_in_four_settings_and_reports_it(tmp_path, capsys):
    from benchmarks.physics import fidelity

    flying = os.path.join(ROOT, "tests", "data", "ant_flying_policy.pt")
    out = str(tmp_path / "fid")
    assert fidelity.main(["--out", out, "--no-train", "--probes", flying, "--candidates", "default", "nov22",
                          "--device", "cpu", "--steps", "20", "--envs", "2", "--native-copies", "2",
                          "--workers", "1"]) == 0
    with open(os.path.join(out, "fidelity.json")) as f:
        probes = json.load(f)["probes"]
    assert [p["candidate"] for p in probes] == ["default", "nov22"]
    from warpgym.tasks.robots import ANT

    for p, n in zip(probes, (ANT.substeps, 3)):  # the task's step, then nov22's 3 substeps
        assert sorted(p["rows"]) == ["finer", "native", "native_finer", "warpgym"]
        assert [p["rows"][k]["substeps"] for k in ("warpgym", "finer", "native", "native_finer")] == [n, 4 * n, n, 4 * n]
        assert isinstance(p["agree"], bool)
    capsys.readouterr()
    assert fidelity.main(["--report", out]) == 0
    table = capsys.readouterr().out
    assert f"| ant_flying_policy.pt | default ({ANT.substeps} substeps) |" in table
    assert "| ant_flying_policy.pt | nov22 (3 substeps) |" in table


def test_every_task_has_defaults_and_the_gpu_default_trains_as_it_was_measured():
    """The GPU default envs were picked by benchmarks/speed/envs_per_gpu.py, which trains with the preset's
    mini-batch: a default whose rollout does not split into that mini-batch would train differently."""
    from agents.config import Config
    from warpgym.tasks.presets import PRESETS
    from warpgym.tasks.registry import task_entry, task_names

    assert set(PRESETS) == set(task_names())  # every task the registry has, PPO has a preset for
    for task in PRESETS:
        for kind in ("cuda", "cpu"):
            envs, iterations = run_setup.default_envs_and_iterations(kind, task)
            assert envs > 0 and iterations > 0, (task, kind)
        envs = run_setup.default_envs_and_iterations("cuda", task)[0]
        cfg = run_setup.build_config(train.parse_args(["--task", task]), task, envs, "cuda:0")
        preset = Config.from_preset(task_entry(task).preset)
        assert cfg.minibatch_size == preset.minibatch_size, (task, envs)
        assert (envs * cfg.horizon_len) % cfg.minibatch_size == 0
        assert cfg.env_args["num_envs"] == envs


def test_config_flags_set_any_ppo_setting_and_name_a_wrong_one():
    args = train.parse_args(["--task", "Hopper-v5", "--config", "gamma=0.999", "--config", "net_dims=64,32",
                             "--config", "batch_size=512", "--config", "normalize_obs=false"])  # batch_size: the earlier name
    cfg = run_setup.build_config(args, "Hopper-v5", 64, "cpu")
    assert (cfg.gamma, cfg.net_dims, cfg.minibatch_size, cfg.normalize_obs) == (0.999, (64, 32), 512, False)
    for bad, says in ((["--config", "gama=0.9"], "'gama' is not a PPO setting"),
                      (["--config", "seed=3"], "'seed' is not a PPO setting"),
                      (["--config", "net_dims=wide"], "comma-separated numbers")):
        with pytest.raises(SystemExit):
            train.parse_args(bad)
