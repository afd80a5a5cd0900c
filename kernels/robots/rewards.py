"""The locomotion reward (Isaac Gym's Ant and Humanoid), computed from an observation row."""

import warp as wp

from kernels.robots.params import LocomotionParams


@wp.func
def locomotion_reward(
    env: int,
    p: LocomotionParams,
    obs: wp.array2d[float],  # (N, O): the row just written for this step
    actions: wp.array2d[float],  # (N, A)
    effort_ratio: wp.array[float],  # (A,) gear / largest gear
    progress: float,  # potential - previous potential [m/s]
):
    num_dofs = actions.shape[1]
    up_proj = obs[env, 10]
    heading_proj = obs[env, 11]
    heading = p.heading_weight
    if heading_proj <= 0.8:
        heading = p.heading_weight * heading_proj / 0.8
    up = float(0.0)
    if up_proj > 0.93:
        up = p.up_weight

    action_sq = float(0.0)
    electricity = float(0.0)
    at_limit = float(0.0)
    for j in range(num_dofs):
        a = actions[env, j]
        pos_scaled = obs[env, 12 + j]
        vel_scaled = obs[env, 12 + num_dofs + j]
        action_sq += a * a
        electricity += wp.abs(a * vel_scaled) * effort_ratio[j]
        if p.scaled_limit_cost != 0:
            excess = wp.abs(pos_scaled) - p.joint_limit_threshold
            if excess > 0.0:
                at_limit += excess / (1.0 - p.joint_limit_threshold) * effort_ratio[j]
        elif pos_scaled > p.joint_limit_threshold:
            at_limit += 1.0

    return (
        progress
        + p.alive_reward
        + up
        + heading
        - p.actions_cost * action_sq
        - p.energy_cost * electricity
        - p.joints_at_limit_cost * at_limit
    )
