"""benchmarks/rllib_vs_warpgym.py --report: the rows of several earlier runs in one table."""

import json
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "benchmarks"))
import rllib_vs_warpgym as cmp  # noqa: E402

COMMON = {"device": "NVIDIA H200", "num_envs": 4096, "seconds": 180.0, "hparams": "preset", "settings": {"Ant": {}}}


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


def test_runs_made_differently_are_refused_by_name(tmp_path):
    first = write(tmp_path / "a", "2026-11-24", [row("warpgym", "/x/Ant-warpgym-1gpu", 1.1e6)])
    other = write(tmp_path / "b", "2026-11-24", [row("rllib", "/x/Ant-rllib-1gpu", 2e4)], num_envs=1024, seconds=60.0)
    with pytest.raises(ValueError, match=r"differ from .* in num_envs, seconds"):
        cmp.merged_reports([first, other])
