"""The one place warpgym reaches into MuJoCo Warp's private modules (mujoco-warp 3.17, pinned in
pyproject.toml): a correction that makes its plane-capsule contacts MuJoCo's.

MuJoCo (``mjc_PlaneCapsule``) aligns the first tangent of a plane-capsule contact with the capsule's
axis projected onto the plane, however steep the capsule. MuJoCo Warp 3.17 does so only while that
projection is at least half the axis's length (the capsule within 60 degrees of the plane) and
otherwise takes a fixed world direction. With a pyramidal friction cone the tangents are the
pyramid's edges, so the friction a steep leg gets differs: Gymnasium's Ant-v5 (condim 3, its ankles
meet the floor steeply) then leaves MuJoCo's trajectory at the first such contact (0.5 rad/s in one
physics step). Frictionless contacts (condim 1: Humanoid) are unaffected.

``mujoco_contact_frames()`` swaps MuJoCo Warp's plane-capsule routine for one with MuJoCo's frame
while a ``MjwSim`` step is built; the narrowphase kernel is cached by the routines it holds, so the
models stepped by Newton (``warpgym.sim.Sim``: warpgym/Ant-v0, Humanoid-v0) keep MuJoCo Warp's as
they were measured. tests/test_suite.py checks the frame against MuJoCo's and that MuJoCo Warp's own
still differs (when it stops differing, this module can go).
"""

from __future__ import annotations

import contextlib
import threading
import types

import warp as wp
from mujoco_warp._src.collision_primitive_core import plane_capsule as _mjw_plane_capsule

_lock = threading.RLock()
_wrapper = None


@wp.func
def _plane_capsule_mujoco_frame(plane_normal: wp.vec3, plane_pos: wp.vec3, capsule_pos: wp.vec3,
                                capsule_axis: wp.vec3, capsule_radius: float, capsule_half_length: float):
    dist, pos, frame = _mjw_plane_capsule(plane_normal, plane_pos, capsule_pos, capsule_axis, capsule_radius,
                                          capsule_half_length)
    n = plane_normal
    tangent = capsule_axis - n * wp.dot(n, capsule_axis)
    size = wp.length(tangent)
    if size > 1.0e-6:  # MuJoCo: the projected axis unless the capsule stands exactly upright
        tangent = tangent / size
        other = wp.cross(n, tangent)
        frame = wp.mat33(n[0], n[1], n[2], tangent[0], tangent[1], tangent[2], other[0], other[1], other[2])
    return dist, pos, frame


def _faithful_wrapper():
    """MuJoCo Warp's plane-capsule wrapper, its source and names unchanged, with its call of the core
    routine bound to ``_plane_capsule_mujoco_frame``."""
    global _wrapper
    if _wrapper is None:
        from mujoco_warp._src import collision_primitive as cp  # noqa: PLC0415

        original = cp.plane_capsule_wrapper.func
        scope = dict(original.__globals__)
        scope["plane_capsule"] = _plane_capsule_mujoco_frame
        scope["__name__"] = __name__ + "_capsule"
        clone = types.FunctionType(original.__code__, scope, original.__name__, original.__defaults__,
                                   original.__closure__)
        clone.__module__ = scope["__name__"]
        clone.__qualname__ = original.__qualname__
        clone.__annotations__ = dict(original.__annotations__)
        clone.__wrapped__ = original
        _wrapper = wp.func(clone)
    return _wrapper


def supported() -> bool:
    try:
        from mujoco_warp._src import collision_primitive as cp  # noqa: PLC0415
        from mujoco_warp._src.types import GeomType  # noqa: PLC0415
    except ImportError:
        return False
    return (GeomType.PLANE, GeomType.CAPSULE) in getattr(cp, "_PRIMITIVE_COLLISIONS", {}) and hasattr(
        cp, "plane_capsule_wrapper")


@contextlib.contextmanager
def mujoco_contact_frames(enabled: bool = True):
    """MuJoCo's plane-capsule contact frames for the MuJoCo Warp kernels launched (or captured) inside."""
    if not enabled or not supported():
        yield
        return
    from mujoco_warp._src import collision_primitive as cp  # noqa: PLC0415
    from mujoco_warp._src.types import GeomType  # noqa: PLC0415

    key = (GeomType.PLANE, GeomType.CAPSULE)
    with _lock:
        before = cp._PRIMITIVE_COLLISIONS[key]
        cp._PRIMITIVE_COLLISIONS[key] = _faithful_wrapper()
        try:
            yield
        finally:
            cp._PRIMITIVE_COLLISIONS[key] = before
