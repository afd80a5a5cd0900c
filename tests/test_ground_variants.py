"""The ground studies' variants of the rough ground (benchmarks/physics/ground_variants.py): the stairs as
heightfields and the whole grid as one heightfield keep the tasks' ground where they promise to, reach the env, and
refuse bad cell sizes by name."""

from dataclasses import replace

import numpy as np
import pytest

from benchmarks.physics.ground_rays import compile_alone, heights, kinds_at
from benchmarks.physics.ground_variants import Resampled
from warpgym.tasks.legged import terrain as tr


def compiled(grid, seed):
    ground = grid.generate(seed)
    return ground, compile_alone(ground)


@pytest.mark.parametrize("make, message", [
    (lambda: Resampled.of(tr.ROUGH, stairs_cell=-0.05), "stairs_cell=-0.05"),
    (lambda: Resampled.of(tr.ROUGH, stairs_cell=3.0), "stairs_cell=3.0"),
    (lambda: Resampled.of(tr.ROUGH, ground_cell=-0.05), "ground_cell=-0.05"),
    (lambda: Resampled.of(tr.ROUGH, stairs_cell=0.05, ground_cell=0.05), "give one of them"),
])
def test_bad_cells_name_the_value_and_the_fix(make, message):
    with pytest.raises(ValueError, match=message):
        make()


def test_stairs_as_heightfields_are_the_boxes_ground_but_at_the_steps_edges():
    """``stairs_cell``: each stairs patch one heightfield (554 ground geoms to 74 on the rough tasks' grid).
    Under rays more than a cell from any step's edge the ground is the boxes' to float32; at the edges it differs by
    at most a step, never more."""
    grid = replace(tr.ROUGH, curriculum=True)
    cell = 0.05
    boxes, boxes_model = compiled(grid, 0)
    fields, fields_model = compiled(Resampled.of(grid, stairs_cell=cell), 0)
    assert (boxes_model.ngeom, fields_model.ngeom) == (554, 74)
    stairs = [c for c, (name, _) in enumerate(grid.sub_terrains) if name.startswith("pyramid_stairs")]
    rng = np.random.default_rng(0)
    points, step = [], 0.0
    for c in stairs:
        for r in range(grid.num_rows):
            corner = boxes.corners[r, c]
            points += [corner[:2] + rng.uniform(0.0, grid.size[0], 2) for _ in range(40)]
            step = max(step, tr._lerp(grid.sub_terrains[c][1].step_height_range, boxes.difficulty[r, c]))
    points = np.array(points)
    want, got = heights(boxes_model, points), heights(fields_model, points)
    # a point is on a step's edge when the boxes' ground a cell away differs from its own
    around = [heights(boxes_model, points + np.array(d)) for d in ((cell, 0), (-cell, 0), (0, cell), (0, -cell))]
    edge = np.any([np.abs(a - want) > 1e-6 for a in around], axis=0)
    assert 0.5 * len(points) < (~edge).sum() < len(points)  # most points lie on a tread, some at an edge
    np.testing.assert_allclose(got[~edge], want[~edge], atol=1e-4)
    assert np.abs(got - want).max() <= step + 1e-4
    assert (fields.origins == boxes.origins).all()


def test_the_whole_ground_as_one_heightfield_is_the_patches_ground_at_its_nodes():
    """``ground_cell``: the grid inside the border as one heightfield (554 ground geoms to 5). At its
    nodes, away from a step's edge, MuJoCo's rays find the patches' ground to float32 (the heightfield patches
    included: the resampling reads them as MuJoCo does, two triangles a cell); between nodes it is resampled, so it
    parts from the patches' ground by at most a step at a step's edge and by millimetres on the heightfield kinds."""
    import mujoco

    grid = replace(tr.ROUGH, curriculum=True)
    cell = 0.05
    patches, patches_model = compiled(grid, 0)
    whole, whole_model = compiled(Resampled.of(grid, ground_cell=cell), 0)
    assert (patches_model.ngeom, whole_model.ngeom) == (554, 5)
    assert whole_model.geom_type[0] == mujoco.mjtGeom.mjGEOM_HFIELD and (whole.origins == patches.origins).all()
    rng = np.random.default_rng(0)
    corner = patches.corners[0, 0, :2]
    extent = np.array([grid.num_rows * grid.size[0], grid.cols * grid.size[1]])
    nodes = corner + cell * rng.integers(0, np.rint(extent / cell).astype(int) + 1, (600, 2))
    want, got = heights(patches_model, nodes), heights(whole_model, nodes)
    # a step's edge: a node of a stairs patch whose ground a cell away is another step's
    stairs = {k for k, (name, _) in enumerate(grid.sub_terrains) if "stairs" in name}
    on_stairs = np.isin(kinds_at(patches, nodes), list(stairs))
    around = [heights(patches_model, nodes + np.array(d)) for d in ((cell, 0), (-cell, 0), (0, cell), (0, -cell))]
    edge = on_stairs & np.any([np.abs(a - want) > 1e-6 for a in around], axis=0)
    assert 0.9 * len(nodes) < (~edge).sum() < len(nodes)
    np.testing.assert_allclose(got[~edge], want[~edge], atol=1e-4)
    anywhere = corner + rng.uniform(0.0, 1.0, (600, 2)) * extent
    err = np.abs(heights(whole_model, anywhere) - heights(patches_model, anywhere))
    steepest = max(tr._lerp(sub.step_height_range, 1.0) for name, sub in grid.sub_terrains if "stairs" in name)
    assert np.median(err) < 1e-3 and err.max() <= steepest + 1e-4


def test_the_whole_ground_heightfield_is_drawn_in_one_colour():
    from warpgym.media.ground_colours import BORDER, PALETTE, colour_ground

    ground, mjm = compiled(Resampled.of(replace(tr.ROUGH, num_rows=2, num_cols=4), ground_cell=0.1), 1)
    colour_ground(mjm, ground)
    np.testing.assert_allclose(mjm.geom_rgba[0, :3], PALETTE[0], atol=1e-6)
    np.testing.assert_allclose(mjm.geom_rgba[1:, :3], np.tile(BORDER, (4, 1)), atol=1e-6)


def test_kinds_at_finds_each_patch_by_its_own_length_and_width():
    """A point's patch on a grid of 8 x 4-m patches (rows along x, columns along y): a patch's start and points
    just inside its corners give its kind; reading both axes by the patch's length would give another patch's."""
    grid = replace(tr.ROUGH, num_rows=3, num_cols=4, size=(8.0, 4.0), curriculum=True)
    ground = grid.generate(0)
    assert len(np.unique(ground.kinds)) > 1  # else any lookup would pass
    starts = ground.origins.reshape(-1, 3)
    inside = np.concatenate([ground.corners.reshape(-1, 3)[:, :2] + d for d in ([0.01, 0.01], [7.99, 3.99])])
    want = ground.kinds.reshape(-1)
    np.testing.assert_array_equal(kinds_at(ground, starts), want)
    np.testing.assert_array_equal(kinds_at(ground, inside), np.concatenate([want, want]))
