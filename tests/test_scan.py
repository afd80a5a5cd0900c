"""Ground scans (kernels.legged.scan, warpgym.sim.rays): MuJoCo Warp's rays aimed and read as mjlab's sensors do,
judged against MuJoCo's own ``mj_ray`` of the same compile, ray by ray, over generated rough ground; mjlab's
patterns by their counts and order."""

import math
from dataclasses import replace

import mujoco
import numpy as np
import pytest
import warp as wp

from warpgym.native.legged import yaw_rotation
from warpgym.sim.rays import RayCaster, Scan, ScanFrames
from warpgym.tasks.legged import terrain as T
from warpgym.tasks.legged.scan import G1_FOOT_SCAN, GO1_FOOT_SCAN, TERRAIN_SCAN, grid_offsets, ring_offsets

# world poses of the scanned body: position, then roll, pitch, yaw [rad]
POSES = [
    # (off the boxes' edges: MuJoCo Warp's float32 rays straight down an edge can miss both boxes beside it)
    ((-4.03, -19.87, 0.45), (0.0, 0.0, 0.7)),  # over the easiest row: stairs of height 0
    ((4.013, -10.987, 0.60), (0.2, 0.3, -2.0)),  # tilted, over the steepest stairs down
    ((3.0, 4.5, 0.80), (0.0, math.pi / 2 - 0.02, 1.0)),  # nose straight down: x axis nearly vertical
    ((-3.0, 22.0, 8.0), (0.0, 0.0, 0.3)),  # high above a slope: every ray beyond 5 m
    ((6.0, -21.0, 0.02), (0.0, 0.0, 0.0)),  # at the foot of a riser, inside the next step
]


def rpy_quat(roll, pitch, yaw):
    q = np.zeros(4)
    mujoco.mju_euler2Quat(q, np.array([roll, pitch, yaw]), "xyz")
    return q


@pytest.fixture(scope="module")
def scene():
    grid = replace(T.ROUGH, num_rows=2, curriculum=True, border_width=2.0)
    spec = mujoco.MjSpec()
    T.add_to_spec(spec, T.generate(grid, seed=3))
    body = spec.worldbody.add_body(name="base", pos=[0, 0, 1])
    body.add_freejoint()
    body.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.3, 0.15, 0.05], group=3)
    for name, y in (("left", 0.1), ("right", -0.1)):
        body.add_site(name=name, pos=[0.15, y, -0.35])
    mjm = spec.compile()
    data = mujoco.MjData(mjm)
    n = len(POSES)
    qpos = np.zeros((n, mjm.nq))
    for w, (pos, rpy) in enumerate(POSES):
        qpos[w, :3], qpos[w, 3:7] = pos, rpy_quat(*rpy)
    with wp.ScopedDevice("cpu"):
        import mujoco_warp as mjw

        m = mjw.put_model(mjm)
        d = mjw.make_data(mjm, nworld=n)
        d.qpos.assign(qpos.astype(np.float32))
        mjw.forward(m, d)
    return mjm, data, m, d, qpos


def native_rays(mjm, data, qpos, kind, obj, pattern, alignment="yaw"):
    """mjlab's recipe in float64 with MuJoCo's own ray: (distance or -1 beyond reach, normal z, frame z) per ray."""
    data.qpos[:] = qpos
    mujoco.mj_forward(mjm, data)
    pos = (data.xpos if kind == "body" else data.site_xpos)[obj].copy()
    mat = (data.xmat if kind == "body" else data.site_xmat)[obj].reshape(3, 3)
    body = obj if kind == "body" else mjm.site_bodyid[obj]
    rot = yaw_rotation(mat) if alignment == "yaw" else mat
    out = []
    for off in pattern.array().astype(np.float64):
        pnt, vec = pos + rot @ off, rot @ np.array(pattern.direction)
        geomid, normal = np.zeros(1, np.int32), np.zeros(3)
        dist = mujoco.mj_ray(mjm, data, pnt, vec, np.array([1, 0, 0, 0, 0, 0], np.uint8), True, body, geomid, normal)
        out.append((dist if 0 <= dist <= pattern.max_distance else -1.0, normal[2], pos[2], pnt[2] + vec[2] * max(dist, 0)))
    return out


def cast(scene, kind, names, pattern):
    mjm, _, m, d, _ = scene
    objtype = mujoco.mjtObj.mjOBJ_BODY if kind == "body" else mujoco.mjtObj.mjOBJ_SITE
    ids = np.array([mujoco.mj_name2id(mjm, objtype, nm) for nm in names])
    bodies = ids if kind == "body" else mjm.site_bodyid[ids]
    scan = Scan(ScanFrames(kind, ids, bodies), pattern.array(), pattern.direction, pattern.alignment,
                pattern.max_distance, num_envs=d.nworld, device="cpu")
    caster = RayCaster(mjm, m, d, pattern.groups, device="cpu")
    caster.sense(scan)
    return scan, ids


def test_mjlabs_patterns_count_and_order_their_rays():
    assert TERRAIN_SCAN.array().shape == (17 * 11, 3)
    g = TERRAIN_SCAN.array()
    # x runs fastest: the first row sweeps x from -0.8 to 0.8 at y = -0.5
    np.testing.assert_allclose(g[:17, 0], np.linspace(-0.8, 0.8, 17), atol=1e-6)
    assert np.all(g[:17, 1] == g[0, 1]) and g[0, 1] == pytest.approx(-0.5) and g[-1, 1] == pytest.approx(0.5)
    ring = GO1_FOOT_SCAN.array()
    assert ring.shape == (5, 3) and np.all(ring[0] == 0) and ring[1, 0] == pytest.approx(0.04)
    assert ring[2] == pytest.approx([0.0, 0.04, 0.0], abs=1e-8)
    assert G1_FOOT_SCAN.array().shape == (7, 3)
    with pytest.raises(ValueError, match="resolution"):
        grid_offsets((1.0, 1.0), 0.0)
    with pytest.raises(ValueError, match="num_samples >= 1"):
        ring_offsets(0.1, 0, include_center=False)


def test_the_height_scan_is_mujocos_own_ray_under_every_grid_point(scene):
    mjm, data, _, d, qpos = scene
    scan, (base,) = cast(scene, "body", ["base"], TERRAIN_SCAN)
    heights = wp.zeros((d.nworld, scan.num_rays), dtype=float, device="cpu")
    scan.heights(heights)
    got, dist = heights.numpy(), scan.s.dist.numpy()
    hits = 0
    for w in range(d.nworld):
        truth = native_rays(mjm, data, qpos[w], "body", base, TERRAIN_SCAN)
        want = np.array([fz - hz if dd >= 0 else TERRAIN_SCAN.max_distance for dd, _, fz, hz in truth])
        np.testing.assert_allclose(got[w], want, atol=2e-4, err_msg=f"world {w}")
        found = np.array([dd >= 0 for dd, *_ in truth])
        assert np.array_equal((dist[w] >= 0) & (dist[w] <= TERRAIN_SCAN.max_distance), found)
        hits += found.sum()
    # the high world misses everything (beyond the reach); the others see ground under most rays
    assert not (dist[3] >= 0).any() or (dist[3] > TERRAIN_SCAN.max_distance).all()
    assert hits > 0.7 * 4 * scan.num_rays
    # the hardest row's stairs are steps: the tilted world's heights take several values, the easiest row's one
    assert len(np.unique(np.round(got[1], 3))) > 3 and len(np.unique(np.round(got[0], 3))) == 1


def test_the_foot_scan_is_the_closest_ground_and_zero_from_inside_it(scene):
    mjm, data, _, d, qpos = scene
    scan, sites = cast(scene, "site", ["left", "right"], GO1_FOOT_SCAN)
    clear = wp.zeros((d.nworld, 2), dtype=float, device="cpu")
    scan.clearance(clear)
    got = clear.numpy()
    inside = 0
    for w in range(d.nworld):
        for f, site in enumerate(sites):
            truth = native_rays(mjm, data, qpos[w], "site", site, GO1_FOOT_SCAN)
            hs = []
            for dd, nz, fz, hz in truth:
                hs.append(GO1_FOOT_SCAN.max_distance if dd < 0 else (0.0 if nz < 0 else fz - hz))
            if all(dd < 0 for dd, *_ in truth):
                want = min(max(truth[0][2], 0.0), GO1_FOOT_SCAN.max_distance)
            else:
                want = min(hs)
            inside += any(dd >= 0 and nz < 0 for dd, nz, *_ in truth)
            assert got[w, f] == pytest.approx(want, abs=2e-4), (w, f)
    # the last world's feet start inside a step: seen from within, the ground is 0 away
    assert inside >= 1 and got[4].min() == pytest.approx(0.0, abs=1e-6)
    # the high world's feet see nothing within 1 m: their own height, clamped to the reach
    assert got[3] == pytest.approx([1.0, 1.0])


def test_bad_scans_name_the_value_and_the_fix(scene):
    mjm, _, m, d, _ = scene
    frames = ScanFrames("body", np.array([1]), np.array([1]))
    with pytest.raises(ValueError, match="alignment='roll'"):
        Scan(frames, TERRAIN_SCAN.array(), alignment="roll")
    with pytest.raises(ValueError, match="max_distance=0"):
        Scan(frames, TERRAIN_SCAN.array(), max_distance=0)
    with pytest.raises(ValueError, match="bodies or sites"):
        Scan(ScanFrames("geom", np.array([1]), np.array([1])), TERRAIN_SCAN.array())
    with pytest.raises(ValueError, match="groups=\\(7,\\)"):
        RayCaster(mjm, m, d, (7,))
