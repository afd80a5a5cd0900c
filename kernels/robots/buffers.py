"""The arrays a locomotion step reads and writes, grouped as Warp structs so that a launch passes
three names instead of twenty arrays (Newton passes its Model, State and Control the same way).

Shapes: N envs, C joint coordinates and D joint dofs per env (root included), A actuated dofs,
B bodies per env, F feet, O observation entries, V MuJoCo dofs per world.
"""

import warp as wp

from kernels.robots.params import LocomotionParams


@wp.struct
class RobotView:
    """One robot per env: the physics state, its constants and what the last step applied."""

    joint_q: wp.array2d[float]  # (N, C) Newton's joint coordinates, root pose first
    joint_qd: wp.array2d[float]  # (N, D) joint velocities, root twist first
    dof_lower: wp.array[float]  # (A,) joint limits [rad]
    dof_upper: wp.array[float]  # (A,)
    default_dof_pos: wp.array[float]  # (A,) the reset pose's joint positions
    effort_ratio: wp.array[float]  # (A,) gear / largest gear
    dof_force: wp.array2d[float]  # (N, A) actuation plus passive force on each joint
    contact_wrench: wp.array2d[float]  # (N*B, 6) contact force and torque on each body
    foot_bodies: wp.array[wp.int32]  # (F,) body index within an env
    bodies_per_env: int
    actions: wp.array2d[float]  # (N, A) the clipped actions applied this step
    warm_start: wp.array2d[float]  # (N, V) MuJoCo's qacc_warmstart, stale after a reset


@wp.struct
class EpisodeBuffers:
    """Per-env accumulators of the running episode, and the statistics of the one that just ended."""

    potential: wp.array[float]  # (N,) -distance to the target / dt at the last step
    length: wp.array[wp.int32]  # (N,) steps so far
    total_return: wp.array[float]  # (N,)
    speed: wp.array[float]  # (N,) forward speed of the episode so far [m/s] (kernels.robots.observations.forward_speed)
    ended_return: wp.array[float]  # (N,) written when an episode ends
    ended_length: wp.array[wp.int32]  # (N,)
    ended_speed: wp.array[float]  # (N,) its forward speed [m/s]
    extra: wp.array2d[float]  # (N, E) this step's value of each of the task's own reward terms (a user's)


@wp.struct
class RobotState:
    """What a term of the robots' tasks reads (``(env: RobotState, w: int[, params]) -> float``): the task's numbers
    (``kernels.robots.params.LocomotionParams``), the robot, the episode's accumulators, and this step's observation
    (``obs[w, 0]``: the torso's height; 10, 11: its up and heading projections; Isaac Gym's layout,
    docs/tensor_api.md)."""

    p: LocomotionParams
    r: RobotView
    ep: EpisodeBuffers
    obs: wp.array2d[float]  # (N, O)
