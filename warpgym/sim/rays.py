"""Ray scans of a MuJoCo Warp scene (``kernels.legged.scan``), cast by MuJoCo Warp's own ``rays`` through its
bounding-volume hierarchy, as mjlab casts them: one render context over the geom groups the scans see, refit once
a step, then every scan's rays. Everything here launches kernels only, so a step's graph can hold it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import warp as wp

from kernels.legged.scan import BASE, WORLD, YAW, RayScan, aim_rays, scan_clearance, scan_heights
from warpgym.sim.checks import check_positive_int

ALIGNMENTS = {"yaw": YAW, "base": BASE, "world": WORLD}


@dataclass
class ScanFrames:
    """Where a scan's rays start: F bodies or F sites of the model, the pattern's R offsets fixed to each."""

    kind: str  # "body" or "site"
    ids: np.ndarray  # (F,) body or site ids
    bodies: np.ndarray  # (F,) the body each frame belongs to (its geoms are not hit when excluded)


class Scan:
    """One scan's buffers (``RayScan``) and the launches that fill them, for ``num_envs`` worlds."""

    def __init__(self, frames: ScanFrames, offsets: np.ndarray, direction=(0.0, 0.0, -1.0), alignment: str = "yaw",
                 max_distance: float = 5.0, exclude_parent_body: bool = True, num_envs: int = 1,
                 device: str = "cpu"):
        if frames.kind not in ("body", "site"):
            raise ValueError(f"a scan's frames are bodies or sites, not {frames.kind!r}: pass kind='body' or 'site'")
        if alignment not in ALIGNMENTS:
            raise ValueError(f"alignment={alignment!r}: pass one of {sorted(ALIGNMENTS)}")
        if not max_distance > 0:
            raise ValueError(f"max_distance={max_distance!r}: pass the rays' reach in metres, e.g. 5.0")
        offsets = np.asarray(offsets, dtype=np.float32).reshape(-1, 3)
        direction = np.asarray(direction, dtype=np.float64)
        if offsets.shape[0] < 1 or not np.linalg.norm(direction) > 0:
            raise ValueError("a scan needs at least one offset and a direction that is not zero")
        self.frames = frames
        self.num_envs = n = check_positive_int("num_envs", num_envs, "pass num_envs >= 1")
        self.num_frames = f = len(frames.ids)
        self.rays_per_frame = r = offsets.shape[0]
        self.device = device
        s = RayScan()
        s.offsets = wp.array(offsets, dtype=wp.vec3, device=device)
        s.direction = wp.vec3(*(direction / np.linalg.norm(direction)))
        s.alignment = ALIGNMENTS[alignment]
        s.max_distance = float(max_distance)
        s.pnt = wp.zeros((n, f * r), dtype=wp.vec3, device=device)
        s.vec = wp.zeros((n, f * r), dtype=wp.vec3, device=device)
        s.dist = wp.zeros((n, f * r), dtype=float, device=device)
        s.geomid = wp.zeros((n, f * r), dtype=wp.int32, device=device)
        s.normal = wp.zeros((n, f * r), dtype=wp.vec3, device=device)
        s.frame_z = wp.zeros((n, f), dtype=float, device=device)
        self.s = s
        self._frames = wp.array(np.asarray(frames.ids, np.int32), dtype=wp.int32, device=device)
        excluded = np.repeat(np.asarray(frames.bodies, np.int32), r) if exclude_parent_body else np.full(f * r, -1)
        self.bodyexclude = wp.array(excluded.astype(np.int32), dtype=int, device=device)

    @property
    def num_rays(self) -> int:
        return self.num_frames * self.rays_per_frame

    def aim(self, d) -> None:
        pos, mat = (d.xpos, d.xmat) if self.frames.kind == "body" else (d.site_xpos, d.site_xmat)
        wp.launch(aim_rays, dim=(self.num_envs, self.num_frames, self.rays_per_frame),
                  inputs=[self.s, self._frames, pos, mat], device=self.device)

    def heights(self, out: wp.array, miss_value: float | None = None) -> None:
        """mjlab's ``height_scan`` into ``out`` (N, F * R): misses read ``miss_value`` (default: the reach)."""
        miss = self.s.max_distance if miss_value is None else float(miss_value)
        wp.launch(scan_heights, dim=(self.num_envs, self.num_rays), inputs=[self.s, miss], outputs=[out],
                  device=self.device)

    def clearance(self, out: wp.array) -> None:
        """mjlab's terrain height sensor, reduced by the minimum, into ``out`` (N, F)."""
        wp.launch(scan_clearance, dim=(self.num_envs, self.num_frames), inputs=[self.s], outputs=[out],
                  device=self.device)


class RayCaster:
    """MuJoCo Warp's ray casting over the geoms of ``groups`` (mjlab's scans see group 0, the terrain)."""

    def __init__(self, mjm, m, d, groups=(0,), device: str = "cpu"):
        import mujoco_warp as mjw  # noqa: PLC0415

        bad = [g for g in groups if not (isinstance(g, int) and 0 <= g < 6)]
        if bad or not groups:
            raise ValueError(f"groups={groups!r}: name geom groups 0-5 the rays may hit, e.g. (0,) for the terrain")
        self._mjw, self.m, self.d, self.device = mjw, m, d, device
        self.groups = tuple(groups)
        # MuJoCo Warp's mask: -1 includes a group, 0 leaves it out
        self.geomgroup = wp.types.vector(6, float)(*[-1.0 if g in self.groups else 0.0 for g in range(6)])
        with wp.ScopedDevice(device):
            self.rc = mjw.create_render_context(mjm, nworld=d.nworld, cam_res=None, use_textures=False,
                                                use_shadows=False, enabled_geom_groups=list(self.groups),
                                                cam_active=[False] * mjm.ncam, render_skybox=False)

    def refit(self) -> None:
        """The hierarchy refit to the geoms' poses of ``d`` (after a forward pass): once a step, before casting."""
        with wp.ScopedDevice(self.device):
            self._mjw.refit_bvh(self.m, self.d, self.rc)

    def cast(self, scan: Scan) -> None:
        """``scan``'s rays as its last ``aim`` left them."""
        s = scan.s
        with wp.ScopedDevice(self.device):
            self._mjw.rays(self.m, self.d, s.pnt, s.vec, self.geomgroup, True, scan.bodyexclude, s.dist, s.geomid,
                           s.normal, self.rc)

    def sense(self, *scans: Scan) -> None:
        """Refit, then aim and cast each scan: the ground as the data's poses see it now."""
        self.refit()
        for scan in scans:
            scan.aim(self.d)
            self.cast(scan)
