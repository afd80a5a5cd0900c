"""Ray-cast scans of the ground, as mjlab's ``RayCastSensor`` and ``TerrainHeightSensor`` make them: a pattern of
rays fixed to each of F frames (bodies or sites), aimed in the frame's yaw (roll and pitch ignored) or its full
orientation, cast by MuJoCo Warp (``warpgym.sim.rays``), then read as heights.

A step of a scan is three launches, all in the step's graph: ``aim_rays`` (origins and directions in the world),
MuJoCo Warp's ``rays`` (distances, geoms and normals), then ``scan_heights`` (mjlab's ``height_scan`` observation)
or ``scan_clearance`` (the foot height scan: the closest ground under each frame), and ``fit_ground_normal`` (the
slope under the base, which the rough Go1's upright term measures tilt against).

Shapes: N worlds, F frames, R rays a frame (F * R rays a world, frame-major as mjlab orders them).
"""

import warp as wp

wp.set_module_options({"enable_backward": False})

YAW = 0  # RayScan.alignment: the frame's heading only, as mjlab's ray_alignment="yaw"
BASE = 1  # the frame's full orientation ("base")
WORLD = 2  # the world's axes ("world")


@wp.struct
class RayScan:
    offsets: wp.array[wp.vec3]  # (R,) ray origins in the frame (mjlab's pattern)
    direction: wp.vec3  # in the frame, unit
    alignment: int  # YAW, BASE or WORLD
    max_distance: float  # a hit further than this counts as a miss
    pnt: wp.array2d[wp.vec3]  # (N, F * R) origins in the world
    vec: wp.array2d[wp.vec3]  # (N, F * R) directions in the world
    dist: wp.array2d[float]  # (N, F * R) MuJoCo Warp's distance to the hit; -1: none
    geomid: wp.array2d[wp.int32]  # (N, F * R)
    normal: wp.array2d[wp.vec3]  # (N, F * R) the surface's normal at the hit (world)
    frame_z: wp.array2d[float]  # (N, F) each frame's height when its rays were aimed


@wp.func
def yaw_rotation(mat: wp.mat33):
    """mjlab's yaw-only rotation: the frame's x axis projected on the ground plane; where it points nearly
    straight up or down (projection under 0.1), the y axis turned a quarter to the right instead."""
    x = wp.vec2(mat[0, 0], mat[1, 0])
    n = wp.length(x)
    if n < 0.1:
        y = wp.vec2(mat[0, 1], mat[1, 1])
        y = y / wp.max(wp.length(y), 1.0e-6)
        x = wp.vec2(y[1], -y[0])
    else:
        x = x / wp.max(n, 1.0e-6)
    return wp.mat33(x[0], -x[1], 0.0, x[1], x[0], 0.0, 0.0, 0.0, 1.0)


@wp.kernel
def aim_rays(s: RayScan, frames: wp.array[wp.int32], frame_pos: wp.array2d[wp.vec3],
             frame_mat: wp.array2d[wp.mat33]):
    """Ray ``i`` of frame ``f``: from the frame's position plus its rotated offset, along its rotated direction.
    ``frame_pos`` / ``frame_mat`` are MuJoCo Warp's ``xpos`` / ``xmat`` (bodies) or ``site_xpos`` /
    ``site_xmat`` (sites), indexed by ``frames``."""
    w, f, i = wp.tid()
    obj = frames[f]
    pos = frame_pos[w, obj]
    rot = wp.identity(3, dtype=float)
    if s.alignment == YAW:
        rot = yaw_rotation(frame_mat[w, obj])
    elif s.alignment == BASE:
        rot = frame_mat[w, obj]
    k = f * s.offsets.shape[0] + i
    s.pnt[w, k] = pos + rot @ s.offsets[i]
    s.vec[w, k] = rot @ s.direction
    if i == 0:
        s.frame_z[w, f] = pos[2]


@wp.func
def hit_z(s: RayScan, w: int, k: int):
    return s.pnt[w, k][2] + s.vec[w, k][2] * wp.max(s.dist[w, k], 0.0)


@wp.func
def hit(s: RayScan, w: int, k: int):
    """A hit within reach (mjlab masks a distance beyond it to -1, a miss)."""
    d = s.dist[w, k]
    return d >= 0.0 and d <= s.max_distance


@wp.kernel
def scan_heights(s: RayScan, miss_value: float, out: wp.array2d[float]):
    """mjlab's ``height_scan`` before its noise and scale: each ray's frame height above its hit, ``miss_value``
    where it hit nothing within reach."""
    w, k = wp.tid()
    h = miss_value
    if hit(s, w, k):
        h = s.frame_z[w, k / s.offsets.shape[0]] - hit_z(s, w, k)
    out[w, k] = h


@wp.kernel
def scan_clearance(s: RayScan, out: wp.array2d[float]):
    """mjlab's ``TerrainHeightSensor`` (reduction "min"): the least height of frame ``f`` above its rays' hits. A
    hit on a surface seen from behind (normal pointing down: the frame is inside the ground) counts 0; a miss
    counts ``max_distance``, or, when every ray of the frame misses, the frame's own height clamped into
    [0, max_distance]."""
    w, f = wp.tid()
    r = s.offsets.shape[0]
    z = s.frame_z[w, f]
    low = float(1.0e30)
    misses = int(0)
    for i in range(r):
        k = f * r + i
        h = s.max_distance
        if hit(s, w, k):
            h = z - hit_z(s, w, k)
            if s.normal[w, k][2] < 0.0:
                h = 0.0
        else:
            misses += 1
        low = wp.min(low, h)
    if misses == r:
        low = wp.clamp(z, 0.0, s.max_distance)
    out[w, f] = low


@wp.kernel
def fit_ground_normal(s: RayScan, picks: wp.array[wp.int32], out: wp.array[wp.vec3]):
    """mjlab's terrain_normal_from_sensors: the plane through the hits of the rays ``picks`` (its evenly spaced
    subsample), its normal the covariance's eigenvector of least eigenvalue, turned upward; straight up where the
    fit says nothing (fewer than 3 hits, points on a line or a heap, a state no longer finite)."""
    w = wp.tid()
    n = int(0)
    centre = wp.vec3(0.0)
    for j in range(picks.shape[0]):
        k = picks[j]
        if hit(s, w, k):
            centre += s.pnt[w, k] + s.vec[w, k] * s.dist[w, k]
            n += 1
    up = wp.vec3(0.0, 0.0, 1.0)
    if n < 3:
        out[w] = up
        return
    centre = centre / float(n)
    cov = wp.mat33(0.0)
    for j in range(picks.shape[0]):
        k = picks[j]
        if hit(s, w, k):
            e = s.pnt[w, k] + s.vec[w, k] * s.dist[w, k] - centre
            cov += wp.outer(e, e)
    finite = True
    for i in range(3):
        for j in range(3):
            if not wp.isfinite(cov[i, j]):
                finite = False
    if not finite:
        out[w] = up
        return
    q, ev = wp.eig3(cov)
    # ascending order of the eigenvalues, as eigh returns them
    lo, mid, top = int(0), int(1), int(2)
    if ev[mid] < ev[lo]:
        lo, mid = mid, lo
    if ev[top] < ev[mid]:
        mid, top = top, mid
    if ev[mid] < ev[lo]:
        lo, mid = mid, lo
    eps = 1.1920929e-07  # float32's machine epsilon
    plane_like = ev[lo] / wp.max(ev[mid], eps) < 0.1
    spread = ev[mid] > wp.max(ev[top], eps) * 1.0e-6
    if not (plane_like and spread):
        out[w] = up
        return
    normal = wp.vec3(q[0, lo], q[1, lo], q[2, lo])
    normal = normal / wp.max(wp.length(normal), 1.0e-8)
    if normal[2] < 0.0:
        normal = -normal
    out[w] = normal
