"""mjlab's terminations of the velocity tasks, one Warp function each: ``(env: LeggedEnv, w: int[, p: Params]) ->
bool``, read after the step's physics. A task's table (``warpgym.tasks.terms.Termination``) says which end an
episode as a failure and which as a time-out (truncated, bootstrapped by the learner); the time limit and a state
that stops being finite are every task's."""

import warp as wp

from kernels.legged.frames import projected_gravity
from kernels.legged.params import ILLEGAL_CONTACT, LeggedEnv

wp.set_module_options({"enable_backward": False})


@wp.struct
class Tilt:
    limit_angle: float  # tilt of the base from upright that ends an episode [rad]


@wp.func
def bad_orientation(env: LeggedEnv, w: int, p: Tilt) -> bool:
    """The base tilted further than the limit from upright (mjlab's fell_over)."""
    g = projected_gravity(env.d.xquat[w, env.r.root_body])
    return wp.abs(wp.acos(wp.clamp(-g[2], -1.0, 1.0))) > p.limit_angle


@wp.func
def illegal_contact(env: LeggedEnv, w: int) -> bool:
    """A contact sensor of the illegal-contact group felt more than the threshold in this step."""
    return env.st.collision_hits[w, ILLEGAL_CONTACT] > 0


@wp.func
def out_of_terrain_bounds(env: LeggedEnv, w: int) -> bool:
    """The base beyond the ground's edge, less the margin (mjlab ends such an episode as a time-out)."""
    pos = env.d.xpos[w, env.r.root_body]
    return wp.abs(pos[0]) > env.t.half_x or wp.abs(pos[1]) > env.t.half_y
