"""mjlab's terrain curriculum (``terrain_levels_vel``) and its bound (``out_of_terrain_bounds``) on a generated grid
whose rows are difficulty levels and whose columns are kinds of ground.

Each world walks on one patch, starting at its origin. When its episode ends, it moves a level up if it walked
further than half a patch, down if it walked less than half the distance its last command asked of a whole episode;
a world past the top level goes to a random level, and none goes below 0. Not on the env's first reset, before any
step: there, the distances say nothing. Its next episode starts from its new patch's origin.

Shapes: N worlds, L levels (rows), C kinds (columns).
"""

import warp as wp

from kernels.common import StepOutputs, resets_world, stream
from kernels.legged.params import LeggedRobot, LeggedState, MjLegged, TerrainLevels
from kernels.legged.random import TERRAIN

wp.set_module_options({"enable_backward": False})


@wp.kernel
def move_levels(t: TerrainLevels, r: LeggedRobot, d: MjLegged, st: LeggedState, force_all: int,
                rng_state: wp.array[wp.int32], out: StepOutputs):
    """Before the reset of the worlds it resets: their levels moved by how far they walked (not before the env's
    first step), their origins set."""
    w = wp.tid()
    if not resets_world(force_all, out, w):
        return
    if st.step_count[0] > 0:
        pos = d.xpos[w, r.root_body]
        dx = pos[0] - t.origin[w][0]
        dy = pos[1] - t.origin[w][1]
        walked = wp.sqrt(dx * dx + dy * dy)
        asked = wp.sqrt(st.command[w, 0] * st.command[w, 0] + st.command[w, 1] * st.command[w, 1])
        up = walked > t.patch_length * 0.5
        down = walked < asked * t.episode_s * 0.5 and not up
        level = t.level[w]
        if up:
            level += 1
        elif down:
            level -= 1
        rows = t.origins.shape[0]
        if level >= rows:
            rng = stream(rng_state, w, TERRAIN)
            level = wp.randi(rng, 0, rows)
        t.level[w] = wp.max(level, 0)
    t.origin[w] = t.origins[t.level[w], t.kind[w]]
