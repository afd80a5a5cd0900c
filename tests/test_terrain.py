"""warpgym's rough ground against mjlab's own (warpgym/tasks/legged/terrain.py): the same seed gives the same
ground, drawn at random or in curriculum mode (one kind a column, as the rough tasks build it), judged by MuJoCo's
ray casts onto both compiles at points spread over the grid and its border
(tests/data/legged/rough_terrain.npz, recorded by ``python -m benchmarks.physics.mjlab_side terrain`` in mjlab's
environment; CI records it afresh), and the patches' starts agree; the generator's own promises hold."""

import os
from dataclasses import replace

import numpy as np
import pytest

from benchmarks.physics.ground_rays import compile_alone, heights
from warpgym.tasks.legged import terrain as tr

HERE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "data", "legged")


def compiled(grid, seed):
    ground = grid.generate(seed)
    return ground, compile_alone(ground)


@pytest.fixture(scope="module")
def reference():
    folder = os.environ.get("WARPGYM_MJLAB_REFERENCE") or HERE
    return np.load(os.path.join(folder, "rough_terrain.npz"))


@pytest.mark.parametrize("prefix, grid", [("", tr.ROUGH), ("curriculum_", replace(tr.ROUGH, curriculum=True))],
                         ids=["random", "curriculum"])
def test_the_same_seed_gives_mjlabs_ground_under_every_ray_and_its_starts(reference, prefix, grid):
    for seed in reference["seeds"]:
        ground, mjm = compiled(grid, int(seed))
        points = reference[f"{prefix}seed{seed}_points"]
        theirs = reference[f"{prefix}seed{seed}_heights"]
        ours = heights(mjm, points)
        assert np.isfinite(theirs).all() and np.isfinite(ours).all()
        # the heightfields hold float32 data: the same cells give the same heights to float32's precision
        assert np.abs(ours - theirs).max() < 1e-5, (seed, np.abs(ours - theirs).max())
        assert np.ptp(theirs) > 1.0  # the ground is not flat: stairs and slopes rise and fall by metres
        np.testing.assert_allclose(ground.origins, reference[f"{prefix}seed{seed}_origins"], atol=1e-9)


def test_a_stairs_patch_rises_a_step_per_ring_and_its_inverse_falls():
    grid = tr.TerrainGrid(sub_terrains=(("up", tr.PyramidStairs(step_height_range=(0.1, 0.1))),
                                        ("down", tr.PyramidStairs(step_height_range=(0.1, 0.1), inverted=True))),
                          num_rows=1, curriculum=True, border_width=0.0)
    ground, mjm = compiled(grid, 0)
    # 8 m patches, 1 m frame, 3 m platform: int((8 - 2 - 3) / 0.6) = 5 rings; the platform 6 steps up (down)
    up, down = ground.corners[0, 0], ground.corners[0, 1]
    rings = [up + np.array([1.0 + 0.3 * k + 0.15, 4.0, 0]) for k in range(5)]
    z = heights(mjm, np.array([p[:2] for p in rings] + [(up + [4, 4, 0])[:2], (down + [4, 4, 0])[:2]]))
    np.testing.assert_allclose(z[:5], 0.1 * np.arange(1, 6), atol=1e-9)
    assert z[5] == pytest.approx(0.6) and z[6] == pytest.approx(-0.6)
    assert ground.origins[0, 0, 2] == pytest.approx(0.6) and ground.origins[0, 1, 2] == pytest.approx(-0.6)


def test_kinds_are_drawn_by_their_proportions_and_difficulties_uniformly():
    """mjlab's rough default draws each patch's kind: over 2000 patches the counts of ROUGH's seven kinds agree with
    its proportions (chi-square below 22.46, the 0.1 % point for 6 degrees of freedom), the difficulties spread
    uniformly over [0, 1] (each tenth within 4 standard deviations of 200)."""
    from dataclasses import replace

    ground = tr.generate(replace(tr.ROUGH, num_rows=40, num_cols=50), seed=3)
    weights = np.array([sub.proportion for _, sub in tr.ROUGH.sub_terrains])
    expected = 2000 * weights / weights.sum()
    counts = np.bincount(ground.kinds.ravel(), minlength=len(weights))
    assert ((counts - expected) ** 2 / expected).sum() < 22.46, counts
    tenths = np.histogram(ground.difficulty, bins=10, range=(0, 1))[0]
    assert np.abs(tenths - 200).max() < 4 * np.sqrt(200 * 0.9), tenths
    # a seed is the ground: the same seed twice, the same kinds; another seed, others
    again = tr.generate(replace(tr.ROUGH, num_rows=40, num_cols=50), seed=3)
    assert (again.kinds == ground.kinds).all()
    assert (tr.generate(replace(tr.ROUGH, num_rows=40, num_cols=50), seed=4).kinds != ground.kinds).any()


@pytest.mark.parametrize("make, message", [
    (lambda: tr.TerrainGrid(sub_terrains=()), "sub_terrains is empty"),
    (lambda: tr.TerrainGrid(sub_terrains=(("flat", tr.Flat(proportion=-1.0)),)), "flat.proportion=-1.0"),
    (lambda: tr.TerrainGrid(sub_terrains=(("flat", tr.Flat()),), difficulty_range=(0.8, 0.2)), "difficulty_range"),
    (lambda: tr.TerrainGrid(sub_terrains=(("flat", tr.Flat()),), num_rows=0), "0 x 20 patches"),
    (lambda: tr.Waves(num_waves=0).patch((8.0, 8.0), 0.5, None), "num_waves=0"),
    (lambda: tr.PyramidSlope(border_width=0.05).patch((8.0, 8.0), 0.5, None), "border_width=0.05"),
])
def test_bad_settings_name_the_value_and_the_fix(make, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        make()


def test_the_picture_colours_each_patch_by_its_kind_and_draws():
    """warpgym.media.terrain_view: every geom of a patch takes its kind's colour, the border grey; the frame is
    drawn where an OpenGL without a display exists (skipped where none does)."""
    from dataclasses import replace

    from warpgym.media import terrain_view as tv
    from warpgym.media.ground_colours import PALETTE

    ground = tr.generate(replace(tr.ROUGH, num_rows=2, num_cols=4), seed=1)
    mjm = tv.compiled(ground)
    at = 0
    for r in range(2):
        for c in range(4):
            for _ in ground.patches[r][c].geoms:
                np.testing.assert_allclose(mjm.geom_rgba[at, :3], PALETTE[ground.kinds[r, c]], atol=1e-6)
                at += 1
    assert mjm.ngeom == at + 4 and np.allclose(mjm.geom_rgba[at:, :3], 0.25)
    from warpgym.media.render import RendererUnavailable

    try:
        frame = tv.draw(ground, 64, 48)
    except RendererUnavailable as e:
        pytest.skip(str(e))
    assert frame.shape == (48, 64, 3) and frame.std() > 5  # a picture, not a blank frame


def test_a_clip_of_a_rough_task_colours_only_the_ground_and_refuses_a_model_of_other_ground():
    """warpgym play's view of a rough task (warpgym.media.legged.LeggedView) colours the task scene's ground by kind:
    the robot's geoms keep theirs; a model compiled from other ground is refused, not coloured wrongly."""
    import mujoco

    from warpgym.media.ground_colours import PALETTE, colour_ground
    from warpgym.tasks.legged import get_legged_task
    from warpgym.tasks.legged.model import compile_task_scene

    compiled, ground = compile_task_scene(get_legged_task("Go1VelocityRough-v0"))
    mjm = compiled.mjm
    before = mjm.geom_rgba.copy()
    colour_ground(mjm, ground)
    terrain = mjm.geom_bodyid == mujoco.mj_name2id(mjm, mujoco.mjtObj.mjOBJ_BODY, "terrain")
    assert np.array_equal(mjm.geom_rgba[~terrain], before[~terrain])
    first = np.flatnonzero(terrain)[0]  # the first patch: row 0, column 0
    np.testing.assert_allclose(mjm.geom_rgba[first, :3], PALETTE[ground.kinds[0, 0]], atol=1e-6)
    assert len({tuple(c) for c in mjm.geom_rgba[terrain, :3].round(3)}) == len(PALETTE) + 1  # 7 kinds, the border
    other = tr.generate(replace(tr.ROUGH, num_rows=2, num_cols=4), seed=1)
    with pytest.raises(ValueError, match="colour the model compiled from this ground"):
        colour_ground(mjm, other)
