"""The rough-ground settings study (benchmarks/physics/rough_settings.py): each variant reaches MuJoCo Warp, and the
ones that only change how contacts are found step the same physics (CPU, 2 worlds)."""

import numpy as np
import pytest

from benchmarks.physics import rough_settings as rs


@pytest.fixture(scope="module")
def rows():
    out, reference = [], None
    for name in ("mjlab", "sap_tile", "njmax_300"):
        row, got = rs.measure("Go1VelocityRough-v0", name, 2, "cpu", steps=1, warmup=1, repeats=1, check_steps=3,
                              reference=reference)
        reference = reference if reference is not None else got
        out.append(row)
    return {r["variant"]: r for r in out}


def test_each_variant_reaches_mujoco_warp(rows):
    # MuJoCo Warp picks its all-pairs broadphase for this scene; the variant's sweep reached its options
    assert rows["mjlab"]["broadphase"] == "NXN" and rows["sap_tile"]["broadphase"] == "SAP_TILE"
    assert rows["mjlab"]["solver_load"]["njmax"] == 1500 and rows["njmax_300"]["solver_load"]["njmax"] == 300


def test_another_broadphase_or_fewer_rows_steps_the_same_physics(rows):
    for name in ("sap_tile", "njmax_300"):
        assert rows[name]["qpos_max_abs_diff"] < 1e-4, name
        assert rows[name]["sensordata_max_abs_diff"] < 1e-3, name  # contact forces up to ~100 N: float32 rounding
        assert rows[name]["worlds_with_other_contact_counts"] == 0, name
        assert rows[name]["worlds_qpos_apart"] == 0, name
        assert rows[name]["faults"]["solver_overflows"] == 0, name
    assert "| sap_tile |" in rs.table(list(rows.values()))


def test_the_reference_is_run_twice_for_the_floor(rows):
    # Warp's CPU backend repeats itself bit for bit: the floor is zero there (on a GPU it is not, see the module)
    floor = rows["mjlab"]["run_to_run"]
    assert floor["qpos_max_abs_diff"] == 0.0 and floor["worlds_qpos_apart"] == 0
    assert "| mjlab |" in rs.table([rows["mjlab"]]) and "| (0) | (0) |" in rs.table([rows["mjlab"]])


def test_agreement_counts_the_worlds_that_moved_apart():
    qpos = np.zeros((3, 4))
    moved = qpos.copy()
    moved[1, 2] = 2 * rs.QPOS_TOL
    moved[2, 0] = rs.QPOS_TOL / 2
    contacts, sensors = np.array([1, 2, 3]), np.zeros((3, 2))
    got = rs.agreement((moved, np.array([1, 2, 4]), sensors), (qpos, contacts, sensors))
    assert got["worlds_qpos_apart"] == 1 and got["worlds_with_other_contact_counts"] == 1
    assert got["qpos_max_abs_diff"] == 2 * rs.QPOS_TOL


@pytest.mark.parametrize("variant", ["stairs_heightfield_5cm", "ground_heightfield_5cm"])
def test_the_ground_variants_reach_the_env_and_step(variant):
    """The ground's variants: the env steps them without faults."""
    row, got = rs.measure("Go1VelocityRough-v0", variant, 2, "cpu", steps=1, warmup=1, repeats=1,
                          check_steps=3, reference=None)
    assert row["faults"]["solver_overflows"] == 0 and row["faults"]["diverged_resets"] == 0
    assert np.isfinite(got[0]).all()


@pytest.mark.parametrize("variant, field, ground_geoms", [("stairs_heightfield_5cm", "stairs_cell", 74),
                                                           ("ground_heightfield_5cm", "ground_cell", 5)])
def test_the_ground_variants_build_fewer_ground_geoms(variant, field, ground_geoms):
    env = rs.build("Go1VelocityRough-v0", 1, "cpu", rs.VARIANTS[variant])
    try:
        assert getattr(env.terrain.grid, field) == 0.05
        names = [env.sim.mjm.geom(i).name for i in range(env.sim.mjm.ngeom)]
        assert sum(n.startswith("terrain_") for n in names) == ground_geoms
    finally:
        env.close()


def test_the_report_prints_a_written_studys_table(rows, tmp_path, capsys):
    import json

    path = tmp_path / "study.json"
    path.write_text(json.dumps({"device": "cpu", "date": "2026-11-29", "rows": list(rows.values())}))
    assert rs.main(["--report", str(path)]) == 0
    printed = capsys.readouterr().out
    assert printed.startswith("cpu, 2026-11-29: 2 worlds, env-steps/s the median of 1 timings; in brackets")
    assert printed.strip().endswith(rs.table(list(rows.values())))
    # a study without the reference's second run has no floor to bracket
    path.write_text(json.dumps({"device": "cpu", "date": "2026-11-29",
                                "rows": [{k: v for k, v in r.items() if k != "run_to_run"} for r in rows.values()]}))
    assert rs.main(["--report", str(path)]) == 0
    assert "in brackets" not in capsys.readouterr().out

