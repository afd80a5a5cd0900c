"""Convex decomposition of a robot's collision meshes: MuJoCo collides a mesh as its convex hull, which fills a
non-convex part's notches (a foot's arch, a hollow shell); with ``RobotFile.convex_decomposition`` on, each
colliding mesh is split by CoACD (Wei et al. 2022; the extra ``convex``: ``pip install 'warpgym[convex]'``) into
convex parts, each a mesh geom of its own that collides as the original did, and the original kept for its mass
and inertia only. A mesh CoACD leaves whole stays as it is.

The parts are cached on disk by the mesh's vertices and faces, the threshold and CoACD's version
(``$WARPGYM_CACHE/convex``, default ``~/.cache/warpgym/convex``), written atomically; read back as plain arrays
(``numpy.load`` without pickles: nothing in a cache file runs).
"""

from __future__ import annotations

import hashlib
import os

import numpy as np

THRESHOLD = 0.05  # CoACD's concavity threshold (its default): lower splits finer
COPIED = ("contype", "conaffinity", "condim", "priority", "friction", "solref", "solimp", "solmix", "margin", "gap")


def cache_dir() -> str:
    return os.path.join(os.environ.get("WARPGYM_CACHE") or os.path.expanduser("~/.cache/warpgym"), "convex")


def _coacd():
    try:
        import coacd  # noqa: PLC0415
    except ImportError:
        raise ValueError("convex_decomposition needs CoACD: pip install 'warpgym[convex]' (or turn it off)") from None
    return coacd


def convex_parts(vert: np.ndarray, face: np.ndarray, threshold: float = THRESHOLD) -> list[tuple[np.ndarray, np.ndarray]]:
    """A closed mesh's convex parts, [(vertices (V, 3), faces (F, 3)), ...], from the cache or from CoACD."""
    from importlib.metadata import PackageNotFoundError, version  # noqa: PLC0415

    try:
        made_by = version("coacd")
    except PackageNotFoundError:
        made_by = "none"
    vert, face = np.ascontiguousarray(vert, "<f8"), np.ascontiguousarray(face, "<i4")
    key = hashlib.sha256(vert.tobytes() + face.tobytes() + f"{threshold!r}:{made_by}".encode()).hexdigest()
    path = os.path.join(cache_dir(), key[:32] + ".npz")
    if os.path.isfile(path):
        with np.load(path, allow_pickle=False) as data:
            return [(data[f"v{i}"], data[f"f{i}"]) for i in range(int(data["count"]))]
    coacd = _coacd()
    coacd.set_log_level("error")
    parts = [(np.asarray(v, float), np.asarray(f, np.int32))
             for v, f in coacd.run_coacd(coacd.Mesh(vert, face), threshold=threshold, seed=0)]
    os.makedirs(cache_dir(), exist_ok=True)
    tmp = f"{path}.{os.getpid()}.tmp"
    with open(tmp, "wb") as f:
        np.savez(f, count=len(parts), **{f"v{i}": v for i, (v, _) in enumerate(parts)},
                 **{f"f{i}": fc for i, (_, fc) in enumerate(parts)})
    os.replace(tmp, path)
    return parts


def decompose(spec, compile_spec, threshold: float = THRESHOLD) -> dict[str, int]:
    """Each colliding mesh geom of ``spec`` split into its convex parts (``<geom>_part<i>``, in the geom's body, with
    its contact settings), the original colliding no more; ``compile_spec(spec)``: MuJoCo's compile of a copy, whose
    meshes (scaled, in their own frames) and geom poses the parts are made from. Returns {geom: parts} of those
    split."""
    import mujoco  # noqa: PLC0415

    m = compile_spec(spec.copy())
    split = {}
    for g in range(m.ngeom):
        if m.geom_type[g] != mujoco.mjtGeom.mjGEOM_MESH or not (m.geom_contype[g] or m.geom_conaffinity[g]):
            continue
        name = mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_GEOM, g)
        mesh = int(m.geom_dataid[g])
        v0, f0 = int(m.mesh_vertadr[mesh]), int(m.mesh_faceadr[mesh])
        vert = m.mesh_vert[v0:v0 + int(m.mesh_vertnum[mesh])]
        face = m.mesh_face[f0:f0 + int(m.mesh_facenum[mesh])]
        parts = convex_parts(vert, face, threshold)
        if len(parts) < 2:
            continue
        rot = np.zeros(9)
        mujoco.mju_quat2Mat(rot, m.geom_quat[g])
        rot, pos = rot.reshape(3, 3), m.geom_pos[g]
        geom = spec.geom(name)
        for i, (v, f) in enumerate(parts, 1):
            part_mesh = spec.add_mesh(name=f"{name}_part{i}", uservert=(v @ rot.T + pos).ravel().tolist(),
                                      userface=f.ravel().tolist())
            part = geom.parent.add_geom(name=f"{name}_part{i}", type=mujoco.mjtGeom.mjGEOM_MESH,
                                        meshname=part_mesh.name, mass=0.0, group=geom.group)
            for field in COPIED:
                value = getattr(geom, field)
                setattr(part, field, value.copy() if hasattr(value, "copy") else value)
        geom.contype = geom.conaffinity = 0  # its mass and inertia stay
        split[name] = len(parts)
    return split
