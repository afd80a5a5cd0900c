"""Kernels behind the Isaac-like Tensor API: pack Newton/MuJoCo Warp arrays into Isaac layouts
and scatter user tensors back into Newton's state.

Layouts (N envs, C joint coordinates and D joint dofs per env, the first 7 coordinates and the first
6 dofs belong to the free root joint; B bodies and K actuated dofs per env):
    joint_q (N, C)      pos 3, quat xyzw 4, then K dof positions
    joint_qd (N, D)     lin vel 3, ang vel 3 (world frame), then K dof velocities
"""

import warp as wp

# Nothing differentiates through these kernels; skipping adjoint code shortens their compile.
wp.set_module_options({"enable_backward": False})

ROOT_COORDS = 7
ROOT_DOFS = 6


@wp.kernel
def pack_root_state(
    joint_q: wp.array2d[float],  # (N, C)
    joint_qd: wp.array2d[float],  # (N, D)
    out: wp.array2d[float],  # (N, 13): pos 3, quat xyzw 4, lin vel 3, ang vel 3
):
    env = wp.tid()
    for i in range(ROOT_COORDS):
        out[env, i] = joint_q[env, i]
    for i in range(ROOT_DOFS):
        out[env, ROOT_COORDS + i] = joint_qd[env, i]


@wp.kernel
def pack_dof_state(
    joint_q: wp.array2d[float],  # (N, C)
    joint_qd: wp.array2d[float],  # (N, D)
    out: wp.array2d[float],  # (N*K, 2): pos, vel
):
    env, dof = wp.tid()
    num_dofs = joint_qd.shape[1] - ROOT_DOFS
    row = env * num_dofs + dof
    out[row, 0] = joint_q[env, ROOT_COORDS + dof]
    out[row, 1] = joint_qd[env, ROOT_DOFS + dof]


@wp.kernel
def pack_rigid_body_state(
    body_q: wp.array[wp.transform],  # (N*B,)
    body_qd: wp.array[wp.spatial_vector],  # (N*B,): lin 3 (COM, world), ang 3 (world)
    out: wp.array2d[float],  # (N*B, 13)
):
    b = wp.tid()
    tf = body_q[b]
    p = wp.transform_get_translation(tf)
    q = wp.transform_get_rotation(tf)
    v = body_qd[b]
    for i in range(3):
        out[b, i] = p[i]
    for i in range(4):
        out[b, 3 + i] = q[i]
    for i in range(6):
        out[b, 7 + i] = v[i]


@wp.kernel
def contact_wrenches_from_mujoco(
    cfrc_ext: wp.array2d[wp.spatial_vector],  # (N, mj bodies): torque 3, force 3 about the subtree COM
    xpos: wp.array2d[wp.vec3],  # (N, mj bodies): body frame origins, same instant as cfrc_ext
    subtree_com: wp.array2d[wp.vec3],  # (N, mj bodies)
    body_rootid: wp.array[wp.int32],  # (mj bodies,)
    mjc_body_to_newton: wp.array2d[wp.int32],  # (N, mj bodies): global Newton body or -1
    out: wp.array2d[float],  # (N*B, 6): force 3, torque 3 about the body origin, world frame
):
    world, mjb = wp.tid()
    body = mjc_body_to_newton[world, mjb]
    if body < 0:
        return
    w = cfrc_ext[world, mjb]
    torque = wp.spatial_top(w)
    force = wp.spatial_bottom(w)
    # MuJoCo refers external wrenches to the root's subtree COM; move the reference to the body origin.
    arm = xpos[world, mjb] - subtree_com[world, body_rootid[mjb]]
    torque = torque - wp.cross(arm, force)
    for i in range(3):
        out[body, i] = force[i]
        out[body, 3 + i] = torque[i]


@wp.kernel
def dof_forces_from_mujoco(
    qfrc_applied: wp.array2d[float],  # (N, nv) MuJoCo dof order
    qfrc_passive: wp.array2d[float],  # (N, nv)
    newton_to_mj_dof: wp.array[wp.int32],  # (K,): actuated Newton dof -> MuJoCo dof, same in every world
    out: wp.array2d[float],  # (N, K)
):
    env, dof = wp.tid()
    j = newton_to_mj_dof[dof]
    out[env, dof] = qfrc_applied[env, j] + qfrc_passive[env, j]


@wp.kernel
def scatter_root_state_indexed(
    states: wp.array2d[float],  # (N, 13)
    env_ids: wp.array[wp.int32],  # (M,)
    joint_q: wp.array2d[float],
    joint_qd: wp.array2d[float],
):
    k = wp.tid()
    env = env_ids[k]
    for i in range(ROOT_COORDS):
        joint_q[env, i] = states[env, i]
    for i in range(ROOT_DOFS):
        joint_qd[env, i] = states[env, ROOT_COORDS + i]


@wp.kernel
def scatter_dof_state_indexed(
    states: wp.array2d[float],  # (N*K, 2)
    env_ids: wp.array[wp.int32],  # (M,)
    joint_q: wp.array2d[float],
    joint_qd: wp.array2d[float],
):
    k, dof = wp.tid()
    env = env_ids[k]
    num_dofs = joint_qd.shape[1] - ROOT_DOFS
    row = env * num_dofs + dof
    joint_q[env, ROOT_COORDS + dof] = states[row, 0]
    joint_qd[env, ROOT_DOFS + dof] = states[row, 1]


@wp.kernel
def scatter_dof_forces(
    forces: wp.array2d[float],  # (N, K)
    joint_f: wp.array2d[float],  # (N, D)
):
    env, dof = wp.tid()
    joint_f[env, ROOT_DOFS + dof] = forces[env, dof]


@wp.kernel
def clear_warmstart_indexed(
    env_ids: wp.array[wp.int32],  # (M,)
    qacc_warmstart: wp.array2d[float],  # (N, nv)
):
    # A state written from outside invalidates the solver's warm start for that world (and a
    # diverged world's warm start may hold NaN that would poison the next solve).
    k, j = wp.tid()
    qacc_warmstart[env_ids[k], j] = 0.0


@wp.kernel
def gather_force_sensors(
    contact_wrench: wp.array2d[float],  # (N*B, 6)
    sensor_bodies: wp.array[wp.int32],  # (F,) body index within an env
    bodies_per_env: int,
    out: wp.array2d[float],  # (N*F, 6): force 3, torque 3
):
    env, k = wp.tid()
    row = env * bodies_per_env + sensor_bodies[k]
    for i in range(6):
        out[env * sensor_bodies.shape[0] + k, i] = contact_wrench[row, i]


@wp.kernel
def clamp_dof_speed(
    max_speed: float,  # [rad/s]
    joint_qd: wp.array2d[float],  # (N, D) in/out
):
    # PhysX clamps articulation joint speeds after each solve; this does the same between substeps.
    env, dof = wp.tid()
    i = ROOT_DOFS + dof
    joint_qd[env, i] = wp.clamp(joint_qd[env, i], -max_speed, max_speed)
