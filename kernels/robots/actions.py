"""Policy actions -> joint torques."""

import warp as wp

from kernels.tensor_api import ROOT_DOFS

# Nothing differentiates through these kernels; skipping adjoint code shortens their compile.
wp.set_module_options({"enable_backward": False})


@wp.kernel
def apply_actions(
    actions_in: wp.array2d[float],  # (N, A) as the policy sent them
    torque_scale: wp.array[float],  # (A,) motor gear * power scale [N m]
    actions: wp.array2d[float],  # (N, A) out: clipped to [-1, 1], non-finite entries zeroed
    joint_f: wp.array2d[float],  # (N, D) out: Newton joint forces, root dofs untouched
    nan_count: wp.array[wp.int32],  # (N,) out: non-finite entries this env sent this step
):
    env = wp.tid()
    bad = int(0)
    for j in range(actions.shape[1]):
        a = actions_in[env, j]
        if not wp.isfinite(a):
            a = 0.0
            bad += 1
        a = wp.clamp(a, -1.0, 1.0)
        actions[env, j] = a
        joint_f[env, ROOT_DOFS + j] = a * torque_scale[j]
    nan_count[env] = bad
