"""How full MuJoCo Warp's constraint and contact buffers get, and which worlds overflowed them.

A world whose constraint rows (``nefc``) exceed ``njmax``, or a batch whose contacts exceed
``naconmax``, loses constraints for that substep: less ground under a tumbling robot. MuJoCo Warp
flags it in ``Data.overflow`` (sticky bits), as it does a geom over more heightfield prisms than MuJoCo keeps
contacts for; these kernels turn the flags into counts."""

import warp as wp

wp.set_module_options({"enable_backward": False})


@wp.kernel
def track_solver_load(
    nefc: wp.array[wp.int32],  # (N,) constraint rows of each world after this substep
    nacon: wp.array[wp.int32],  # (1,) contacts of all worlds after this substep
    drop_bits: wp.int32,  # overflow bits that mean constraints or contacts were dropped
    first_substep: wp.int32,  # 1 on a step's first substep: the step's counts start again
    overflow: wp.array[wp.int32],  # (N,) in/out: MuJoCo Warp's bits; the drop bits are cleared here
    peak_nefc: wp.array[wp.int32],  # (N,) in/out: most constraint rows seen in each world
    peak_nacon: wp.array[wp.int32],  # (1,) in/out: most contacts seen in one substep, all worlds
    overflowed: wp.array[wp.int32],  # (N,) in/out: substeps of this step that dropped constraints
):
    world = wp.tid()
    peak_nefc[world] = wp.max(peak_nefc[world], nefc[world])
    if world == 0:
        peak_nacon[0] = wp.max(peak_nacon[0], nacon[0])
    dropped = int(0)
    if (overflow[world] & drop_bits) != 0:
        dropped = 1
        overflow[world] = overflow[world] & ~drop_bits
    if first_substep != 0:
        overflowed[world] = dropped
    else:
        overflowed[world] = overflowed[world] + dropped
