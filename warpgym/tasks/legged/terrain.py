"""Generated rough ground as mjlab 1.6 defines it (``mjlab.terrains``, ``ROUGH_TERRAINS_CFG``): a grid of square
patches of seven kinds (flat, stairs up, stairs down, slopes up and down, random bumps, waves), each built as MuJoCo
geometry (boxes for the flat patch and the stairs, heightfields for the rest) inside a flat border.

A patch's geometry is computed here as plain data (``Box``, ``HField``) and only then added to an ``mujoco.MjSpec``,
so that its heights can be read without MuJoCo. The numbers are mjlab's: the same sub-terrain parameters, the same
draws from one ``numpy.random.Generator`` in the same order (a patch's kind, then its difficulty, then its own
draws), the same box sizes and heightfield data, so that a seed gives mjlab's terrain; tests/test_terrain.py casts
rays onto both compiles and compares the heights.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

MIN_BORDER_HEIGHT = 0.05  # a stairs patch's frame keeps this depth when its steps are flat (mjlab's)


@dataclass(frozen=True)
class Box:
    pos: tuple[float, float, float]  # centre, in the patch's frame (its corner at the origin)
    half: tuple[float, float, float]


@dataclass(frozen=True)
class HField:
    pos: tuple[float, float, float]  # the geom's centre
    size: tuple[float, float, float, float]  # MuJoCo's hfield size: half x, half y, elevation, base
    data: np.ndarray = field(repr=False)  # (nrow, ncol) in [0, 1], row-major as MuJoCo reads it


@dataclass(frozen=True)
class Patch:
    origin: tuple[float, float, float]  # where a robot starts on it, in the patch's frame
    geoms: tuple  # Box and HField


def _border(size, inner, height, center) -> list[Box]:
    """Four boxes around an ``inner`` rectangle inside ``size``, centred at ``center`` (mjlab's make_border)."""
    tx, ty = (size[0] - inner[0]) / 2.0, (size[1] - inner[1]) / 2.0
    cx, cy, cz = center
    return [Box((cx, cy + inner[1] / 2.0 + ty / 2.0, cz), (size[0] / 2.0, ty / 2.0, height / 2.0)),
            Box((cx, cy - inner[1] / 2.0 - ty / 2.0, cz), (size[0] / 2.0, ty / 2.0, height / 2.0)),
            Box((cx - inner[0] / 2.0 - tx / 2.0, cy, cz), (tx / 2.0, inner[1] / 2.0, height / 2.0)),
            Box((cx + inner[0] / 2.0 + tx / 2.0, cy, cz), (tx / 2.0, inner[1] / 2.0, height / 2.0))]


def _half(dims) -> tuple[float, float, float]:
    return tuple(max(1e-6, d / 2.0) for d in dims)


def _lerp(span: tuple[float, float], t: float) -> float:
    return span[0] + t * (span[1] - span[0])


@dataclass(frozen=True)
class Flat:
    proportion: float = 1.0

    def patch(self, size, difficulty: float, rng) -> Patch:
        return Patch((size[0] / 2, size[1] / 2, 0.0), (Box((size[0] / 2.0, size[1] / 2.0, -0.5),
                                                           (size[0] / 2.0, size[1] / 2.0, 0.5)),))


@dataclass(frozen=True)
class PyramidStairs:
    """Square rings of steps around a platform, up (or, ``inverted``, down) towards the centre."""

    proportion: float = 1.0
    step_height_range: tuple[float, float] = (0.0, 0.2)
    step_width: float = 0.3
    platform_width: float = 3.0
    border_width: float = 1.0
    inverted: bool = False

    def patch(self, size, difficulty: float, rng) -> Patch:
        h = _lerp(self.step_height_range, difficulty)
        w = self.step_width
        steps = max(0, int(min(int((size[i] - 2 * self.border_width - self.platform_width) / (2 * w)) for i in (0, 1))))
        total = (steps + 1) * h
        geoms: list[Box] = []
        if self.border_width > 0.0:
            depth = max(h, MIN_BORDER_HEIGHT)
            inner = (size[0] - 2 * self.border_width, size[1] - 2 * self.border_width)
            geoms += _border(size, inner, depth, (0.5 * size[0], 0.5 * size[1], -0.5 * depth))
        cx, cy = 0.5 * size[0], 0.5 * size[1]
        tx, ty = size[0] - 2 * self.border_width, size[1] - 2 * self.border_width
        for k in range(steps):
            if self.inverted:
                z, height = -total / 2 - (k + 1) * h / 2.0, total - (k + 1) * h
            else:
                z, height = k * h / 2.0, (k + 2) * h
            ring = (tx - 2 * k * w, ty - 2 * k * w)
            offset = (k + 0.5) * w
            along_x, along_y = _half((ring[0], w, height)), _half((w, ring[1] - 2 * w, height))
            geoms += [Box((cx, cy + ty / 2.0 - offset, z), along_x), Box((cx, cy - ty / 2.0 + offset, z), along_x),
                      Box((cx + tx / 2.0 - offset, cy, z), along_y), Box((cx - tx / 2.0 + offset, cy, z), along_y)]
        top = (tx - 2 * steps * w, ty - 2 * steps * w)
        if self.inverted:
            geoms.append(Box((cx, cy, -total - h / 2), _half((*top, h))))
            return Patch((cx, cy, -(steps + 1) * h), tuple(geoms))
        geoms.append(Box((cx, cy, steps * h / 2), _half((*top, (steps + 2) * h))))
        return Patch((cx, cy, (steps + 1) * h), tuple(geoms))


def _hfield(noise: np.ndarray, size, vertical_scale: float, base_ratio: float, z: float) -> HField:
    """An integer height grid as MuJoCo's heightfield: normalised to [0, 1], its range as the elevation.

    The grid's first axis is x in mjlab's arrays and MuJoCo reads it as rows (y): the field is laid down as mjlab
    lays it, transposed on square patches, so that the ground is the same."""
    lo, hi = int(noise.min()), int(noise.max())
    span = hi - lo if hi != lo else 1
    height = span * vertical_scale
    data = (noise - lo) / span if hi != lo else np.zeros(noise.shape)
    return HField((size[0] / 2, size[1] / 2, z), (size[0] / 2, size[1] / 2, height, height * base_ratio),
                  data.astype(np.float32))


def _inset(noise_shape, border: int, inner: np.ndarray) -> np.ndarray:
    noise = np.zeros(noise_shape, dtype=np.int16)
    noise[border : noise_shape[0] - border, border : noise_shape[1] - border] = np.rint(inner).astype(np.int16)
    return noise


@dataclass(frozen=True)
class _Heightfield:
    """What the heightfield kinds share: a grid of ``horizontal_scale`` cells, heights in ``vertical_scale`` steps,
    a flat frame ``border_width`` wide, a base under the lowest point of ``base_thickness_ratio`` of the range."""

    proportion: float = 1.0
    border_width: float = 0.25
    horizontal_scale: float = 0.1
    vertical_scale: float = 0.005
    base_thickness_ratio: float = 1.0

    def cells(self, size) -> tuple[int, int, int, int, int]:
        """The frame's cells, the patch's cells along x and y, and those inside the frame."""
        border = int(self.border_width / self.horizontal_scale)
        if 0 < self.border_width < self.horizontal_scale:
            raise ValueError(f"border_width={self.border_width} is under horizontal_scale={self.horizontal_scale}: "
                             f"a border must be at least one cell wide (make it 0 or >= {self.horizontal_scale})")
        wide, long = int(size[0] / self.horizontal_scale), int(size[1] / self.horizontal_scale)
        return border, wide, long, wide - 2 * border, long - 2 * border


@dataclass(frozen=True)
class PyramidSlope(_Heightfield):
    """A four-sided slope up (or, ``inverted``, down) to a flat platform at the centre, as a heightfield."""

    slope_range: tuple[float, float] = (0.0, 0.7)
    platform_width: float = 2.0
    inverted: bool = False

    def patch(self, size, difficulty: float, rng) -> Patch:
        slope = _lerp(self.slope_range, difficulty) * (-1 if self.inverted else 1)
        border, wide, long, iw, il = self.cells(size)
        peak = int(slope * (iw * self.horizontal_scale if border else size[0]) / 2 / self.vertical_scale)
        cx, cy = int(iw / 2), int(il / 2)
        xx = ((cx - np.abs(cx - np.arange(iw))) / cx).reshape(iw, 1)
        yy = ((cy - np.abs(cy - np.arange(il))) / cy).reshape(1, il)
        raw = peak * xx * yy
        flat = int(self.platform_width / self.horizontal_scale / 2)
        px, py = iw // 2 - flat, il // 2 - flat
        top = raw[px, py] if px >= 0 and py >= 0 else 0
        noise = _inset((wide, long), border, np.clip(raw, min(0, top), max(0, top)))
        field = _hfield(noise, size, self.vertical_scale, self.base_thickness_ratio, 0.0)
        z = -field.size[2] if self.inverted else 0.0
        field = HField((field.pos[0], field.pos[1], z), field.size, field.data)
        return Patch((size[0] / 2, size[1] / 2, z if self.inverted else field.size[2]), (field,))


@dataclass(frozen=True)
class RandomUniform(_Heightfield):
    """Bumps: heights drawn uniformly from a quantised range at every cell (mjlab's ``random_rough``)."""

    noise_range: tuple[float, float] = (0.02, 0.10)
    noise_step: float = 0.02

    def patch(self, size, difficulty: float, rng) -> Patch:
        border, wide, long, iw, il = self.cells(size)
        inner = (iw * self.horizontal_scale, il * self.horizontal_scale) if border else tuple(size)
        # mjlab draws at a downsampled grid and fits a spline through it; at its default (one draw per cell) the
        # two grids are the same points and the spline returns the draws, which is what this keeps
        dw, dl = int(inner[0] / self.horizontal_scale), int(inner[1] / self.horizontal_scale)
        if (dw, dl) != (iw, il):
            raise ValueError(f"RandomUniform: {size} m patches with border_width={self.border_width} give a "
                             f"{dw}x{dl} draw grid against {iw}x{il} cells; only equal grids are supported")
        lo, hi = int(self.noise_range[0] / self.vertical_scale), int(self.noise_range[1] / self.vertical_scale)
        step = int(self.noise_step / self.vertical_scale)
        draws = rng.choice(np.arange(lo, hi + step, step), size=(dw, dl))
        noise = _inset((wide, long), border, draws)
        field = _hfield(noise, size, self.vertical_scale, self.base_thickness_ratio, 0.0)
        return Patch((size[0] / 2, size[1] / 2, sum(self.noise_range) / 2), (field,))


@dataclass(frozen=True)
class Waves(_Heightfield):
    """Crossed sine waves, ``num_waves`` along the patch, of an amplitude that grows with difficulty."""

    base_thickness_ratio: float = 0.25
    amplitude_range: tuple[float, float] = (0.0, 0.2)
    num_waves: int = 4

    def patch(self, size, difficulty: float, rng) -> Patch:
        if self.num_waves <= 0:
            raise ValueError(f"Waves: num_waves={self.num_waves}: give at least 1")
        border, wide, long, iw, il = self.cells(size)
        amp = int(0.5 * _lerp(self.amplitude_range, difficulty) / self.vertical_scale)
        k = 2 * np.pi / (il / self.num_waves)
        raw = amp * (np.cos(np.arange(il).reshape(1, il) * k) + np.sin(np.arange(iw).reshape(iw, 1) * k))
        noise = _inset((wide, long), border, raw)
        field = _hfield(noise, size, self.vertical_scale, self.base_thickness_ratio, 0.0)
        field = HField((field.pos[0], field.pos[1], -field.size[2] / 2), field.size, field.data)
        return Patch((size[0] / 2, size[1] / 2, 0.0), (field,))


@dataclass(frozen=True)
class TerrainGrid:
    """``num_rows`` x ``num_cols`` patches of ``size`` metres, centred at the origin, inside a border. Rows are the
    curriculum's levels. ``curriculum=False`` (mjlab's rough default) draws each patch's kind by ``proportion`` and
    its difficulty uniformly; ``curriculum=True`` gives each kind one column and raises difficulty along rows."""

    sub_terrains: tuple[tuple[str, object], ...]
    size: tuple[float, float] = (8.0, 8.0)
    border_width: float = 20.0
    border_height: float = 1.0
    num_rows: int = 10
    num_cols: int = 20
    curriculum: bool = False
    difficulty_range: tuple[float, float] = (0.0, 1.0)

    def __post_init__(self):
        if not self.sub_terrains:
            raise ValueError("TerrainGrid: sub_terrains is empty: name at least one, e.g. (('flat', Flat()),)")
        for name, sub in self.sub_terrains:
            if not sub.proportion >= 0:
                raise ValueError(f"TerrainGrid: {name}.proportion={sub.proportion}: give a weight >= 0")
        lo, hi = self.difficulty_range
        if not 0 <= lo <= hi:
            raise ValueError(f"TerrainGrid: difficulty_range={self.difficulty_range}: give 0 <= min <= max")
        if self.num_rows < 1 or self.num_cols < 1:
            raise ValueError(f"TerrainGrid: {self.num_rows} x {self.num_cols} patches: give at least 1 x 1")

    @property
    def cols(self) -> int:
        return len(self.sub_terrains) if self.curriculum else self.num_cols

    def generate(self, seed: int) -> Terrain:
        """The ground the tasks lay (``generate``); a grid that lays its patches otherwise overrides this."""
        return generate(self, seed)


# mjlab 1.6's ROUGH_TERRAINS_CFG
ROUGH = TerrainGrid(sub_terrains=(
    ("flat", Flat(proportion=0.2)),
    ("pyramid_stairs", PyramidStairs(proportion=0.2, step_height_range=(0.0, 0.1))),
    ("pyramid_stairs_inv", PyramidStairs(proportion=0.2, step_height_range=(0.0, 0.1), inverted=True)),
    ("hf_pyramid_slope", PyramidSlope(proportion=0.1, slope_range=(0.0, 1.0))),
    ("hf_pyramid_slope_inv", PyramidSlope(proportion=0.1, slope_range=(0.0, 1.0), inverted=True)),
    ("random_rough", RandomUniform(proportion=0.1)),
    ("wave_terrain", Waves(proportion=0.1)),
))


@dataclass
class Terrain:
    """A generated grid: each patch's kind (an index into ``grid.sub_terrains``), difficulty, corner and the
    robots' start on it (world frame), and its geometry (in the patch's frame)."""

    grid: TerrainGrid
    kinds: np.ndarray  # (rows, cols) int
    difficulty: np.ndarray  # (rows, cols)
    corners: np.ndarray  # (rows, cols, 3)
    origins: np.ndarray  # (rows, cols, 3)
    patches: list[list[Patch]]

    def patch_geoms(self):
        """The patches' geoms in the world frame, patch by patch in row-major order."""
        for r in range(self.grid.num_rows):
            for c in range(self.grid.cols):
                corner = self.corners[r, c]
                for g in self.patches[r][c].geoms:
                    pos = tuple(float(p + o) for p, o in zip(g.pos, corner))
                    yield Box(pos, g.half) if isinstance(g, Box) else HField(pos, g.size, g.data)

    def patch_geom_kinds(self) -> list[int]:
        """The kind of each of ``patch_geoms``' geoms, in their order (what colours the ground by kind)."""
        return [int(self.kinds[r, c]) for r in range(self.grid.num_rows) for c in range(self.grid.cols)
                for _ in self.patches[r][c].geoms]

    def boxes_and_fields(self):
        """Every geom in the world frame: ``patch_geoms``, then the outer border's four boxes."""
        yield from self.patch_geoms()
        g = self.grid
        if g.border_width > 0.0:
            inner = (g.num_rows * g.size[0], g.cols * g.size[1])
            outer = (inner[0] + 2 * g.border_width, inner[1] + 2 * g.border_width)
            yield from _border(outer, inner, abs(g.border_height), (0.0, 0.0, -g.border_height / 2))


def generate(grid: TerrainGrid, seed: int) -> Terrain:
    """The grid's patches drawn from ``numpy.random.default_rng(seed)`` in mjlab's order."""
    rng = np.random.default_rng(seed)
    rows, cols = grid.num_rows, grid.cols
    kinds = np.zeros((rows, cols), dtype=np.int64)
    difficulty = np.zeros((rows, cols))
    corners = np.zeros((rows, cols, 3))
    origins = np.zeros((rows, cols, 3))
    patches: list[list] = [[None] * cols for _ in range(rows)]
    weights = np.array([sub.proportion for _, sub in grid.sub_terrains], dtype=np.float64)
    if not grid.curriculum and weights.sum() <= 0:
        raise ValueError("TerrainGrid: every proportion is 0: give at least one kind a weight")
    weights = weights / weights.sum() if weights.sum() > 0 else weights
    # mjlab's order: column by column in curriculum mode, row by row otherwise
    order = ([(r, c) for c in range(cols) for r in range(rows)] if grid.curriculum
             else [(r, c) for r in range(rows) for c in range(cols)])
    for r, c in order:
        if grid.curriculum:
            kind = c
            d = _lerp(grid.difficulty_range, r / max(rows - 1, 1))
        else:
            kind = int(rng.choice(len(weights), p=weights))
            d = float(rng.uniform(*grid.difficulty_range))
        corner = np.array([-rows * grid.size[0] * 0.5 + r * grid.size[0], -cols * grid.size[1] * 0.5 + c * grid.size[1], 0.0])
        patch = grid.sub_terrains[kind][1].patch(grid.size, d, rng)
        kinds[r, c], difficulty[r, c], corners[r, c] = kind, d, corner
        origins[r, c] = np.asarray(patch.origin) + corner
        patches[r][c] = patch
    return Terrain(grid, kinds, difficulty, corners, origins, patches)


def add_to_spec(spec, terrain: Terrain, body_name: str = "terrain") -> None:
    """The terrain's geoms on the world body ``body_name`` of ``spec`` (an ``mujoco.MjSpec``; made when the spec has
    none, as the rough tasks' scenes have an empty one), massless, named in order."""
    import mujoco  # noqa: PLC0415

    body = spec.body(body_name) or spec.worldbody.add_body(name=body_name)
    for i, g in enumerate(terrain.boxes_and_fields()):
        if isinstance(g, Box):
            body.add_geom(name=f"terrain_{i}", type=mujoco.mjtGeom.mjGEOM_BOX, size=list(g.half), pos=list(g.pos),
                          mass=0)
        else:
            hf = spec.add_hfield(name=f"terrain_hfield_{i}", size=list(g.size), nrow=g.data.shape[0],
                                 ncol=g.data.shape[1], userdata=g.data.flatten().tolist())
            body.add_geom(name=f"terrain_{i}", type=mujoco.mjtGeom.mjGEOM_HFIELD, hfieldname=hf.name,
                          pos=list(g.pos), mass=0)
