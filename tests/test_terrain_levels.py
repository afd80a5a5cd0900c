"""The rough ground's curriculum (kernels.legged.terrain_levels, warpgym.tasks.legged.levels): where worlds start, how
their level moves when an episode ends (mjlab's terrain_levels_vel), and the ground's bound (out_of_terrain_bounds),
each checked against numbers worked out from mjlab's rules."""

from dataclasses import replace

import numpy as np
import pytest
import warp as wp

from kernels.common import StepOutputs
from kernels.legged.params import LeggedRobot, LeggedState, MjLegged
from kernels.legged.terrain_levels import TerrainLevels, move_levels
from warpgym.tasks.legged import terrain as T
from warpgym.tasks.legged.levels import bounds, proportional_counts, start_levels

CURRICULUM = replace(T.ROUGH, curriculum=True)


def chi_square(counts) -> float:
    """Pearson's statistic of ``counts`` against equal expected counts."""
    counts = np.asarray(counts, dtype=np.float64)
    expected = counts.sum() / len(counts)
    return float(((counts - expected) ** 2 / expected).sum())


@pytest.fixture(scope="module")
def ground():
    return T.generate(CURRICULUM, seed=0)


def test_worlds_are_shared_among_kinds_by_proportion_one_each_first():
    p = np.array([0.2, 0.2, 0.2, 0.1, 0.1, 0.1, 0.1])
    # 10 worlds: one each, then 3 left: ideal 0.6 for the first three kinds, 0.3 for the rest, floors 0
    assert proportional_counts(10, p).tolist() == [2, 2, 2, 1, 1, 1, 1]
    # 3 worlds, fewer than kinds: none first, the three largest remainders get one
    assert proportional_counts(3, p).tolist() == [1, 1, 1, 0, 0, 0, 0]
    # 4096: one each, then 4089 by proportion: 817.8 x 3 and 408.9 x 4 floor to 4083; the 6 left go to the
    # remainders 0.9 (all four) and then 0.8 (the first two)
    assert proportional_counts(4096, p).tolist() == [819, 819, 818, 410, 410, 410, 410]


def test_first_levels_are_uniform_up_to_the_initial_cap_and_kinds_fixed_in_blocks(ground):
    levels, kinds = start_levels(ground, 7000, max_init_level=5, rng=np.random.default_rng(0))
    assert levels.min() == 0 and levels.max() == 5
    assert chi_square(np.bincount(levels, minlength=6)) < 20.52  # the 0.1 % point for 5 degrees of freedom
    assert np.all(np.diff(kinds) >= 0) and np.bincount(kinds).tolist() == proportional_counts(7000, [0.2] * 3 + [0.1] * 4).tolist()
    # a cap above the grid's levels is the top level
    levels, _ = start_levels(ground, 2000, max_init_level=50, rng=np.random.default_rng(1))
    assert levels.max() == CURRICULUM.num_rows - 1
    with pytest.raises(ValueError, match="curriculum=True"):
        start_levels(T.generate(replace(T.ROUGH, num_rows=1, num_cols=1), 0), 4, 5, np.random.default_rng(0))
    with pytest.raises(ValueError, match="max_init_level=-1"):
        start_levels(ground, 4, -1, np.random.default_rng(0))


def test_the_bound_is_the_ground_with_its_border_less_the_margin(ground):
    # 10 levels x 8 m along x, 7 kinds x 8 m along y, 20 m of border, 0.3 m of margin
    assert bounds(ground) == pytest.approx((40.0 + 20.0 - 0.3, 28.0 + 20.0 - 0.3))


def launch_moves(ground, start_level, kind, walked, command, done, force_all=0, steps=5, seed=0):
    n = len(start_level)
    t = TerrainLevels()
    t.origins = wp.array(ground.origins.astype(np.float32), dtype=wp.vec3)
    t.level = wp.array(np.asarray(start_level, np.int32), dtype=wp.int32)
    t.kind = wp.array(np.asarray(kind, np.int32), dtype=wp.int32)
    origin = ground.origins[np.asarray(start_level), np.asarray(kind)].astype(np.float32)
    t.origin = wp.array(origin, dtype=wp.vec3)
    t.patch_length, t.episode_s = 8.0, 20.0
    t.half_x, t.half_y = bounds(ground)
    r = LeggedRobot()
    r.root_body = 1
    d = MjLegged()
    xpos = np.zeros((n, 2, 3), np.float32)
    xpos[:, 1] = origin + np.asarray(walked, np.float32)
    d.xpos = wp.array(xpos, dtype=wp.vec3)
    st = LeggedState()
    st.command = wp.array(np.asarray(command, np.float32), dtype=float)
    st.step_count = wp.array([steps], dtype=wp.int32)
    out = StepOutputs()
    for name in ("terminated", "truncated", "time_outs", "done"):
        setattr(out, name, wp.array(np.asarray(done, bool), dtype=wp.bool))
    rng = wp.array(np.array([seed, steps], np.int32), dtype=wp.int32)  # (seed, step counter), as the env's
    wp.launch(move_levels, dim=n, inputs=[t, r, d, st, force_all, rng, out])
    return t.level.numpy(), t.origin.numpy()


def test_levels_move_up_for_half_a_patch_down_for_half_the_asked_distance(ground):
    cases = [  # start level, walked (x, y, z), command (vx, vy, yaw rate), episode ended, level after
        (3, (4.1, 0.0, 0.0), (1.0, 0.0, 0.0), True, 4),  # beyond half a patch (4 m): up
        (3, (3.0, 2.9, 0.0), (0.0, 0.0, 0.0), True, 4),  # 4.17 m diagonally: up
        (3, (1.0, 0.0, 0.0), (1.0, 0.0, 0.0), True, 2),  # asked 1 m/s for 20 s: less than 10 m walked, down
        (3, (3.0, 0.0, 0.0), (0.2, 0.2, 0.0), True, 3),  # asked 0.28 m/s: 2.8 m is half, 3 m walked: stays
        (3, (1.0, 0.0, 5.0), (0.0, 0.0, 1.0), True, 3),  # only turning asked: nothing to fall short of
        (0, (0.0, 0.0, 0.0), (1.0, 0.0, 0.0), True, 0),  # down from the lowest level: stays
        (3, (9.0, 0.0, 0.0), (0.0, 0.0, 0.0), False, 3),  # its episode goes on: untouched
    ]
    level, kind = [c[0] for c in cases], [2] * len(cases)
    got, origin = launch_moves(ground, level, kind, [c[1] for c in cases], [c[2] for c in cases], [c[3] for c in cases])
    assert got.tolist() == [c[4] for c in cases]
    np.testing.assert_allclose(origin, ground.origins[got, 2], atol=1e-5)
    # the env's first reset, before any step: levels stay, the starts are those of the levels
    got, _ = launch_moves(ground, level, kind, [c[1] for c in cases], [c[2] for c in cases], [True] * len(cases),
                          force_all=1, steps=0)
    assert got.tolist() == level


def test_past_the_top_level_a_world_goes_to_a_uniformly_drawn_level(ground):
    n, top = 5000, CURRICULUM.num_rows - 1
    got, _ = launch_moves(ground, [top] * n, np.arange(n) % 7, [(5.0, 0.0, 0.0)] * n, [(0.5, 0.0, 0.0)] * n,
                          [True] * n, seed=7)
    counts = np.bincount(got, minlength=CURRICULUM.num_rows)
    assert len(counts) == CURRICULUM.num_rows and chi_square(counts) < 27.88  # the 0.1 % point for 9 d.o.f.
