"""Task constants as a Warp struct, filled from a task dataclass in ``warpgym/tasks`` (the one source
of the numbers) and passed to the kernels by value."""

import warp as wp


@wp.struct
class LocomotionParams:
    dt: float  # control step [s]; potentials are distances over dt
    target: wp.vec3  # walk target in each env's frame [m]
    start_pos: wp.vec3  # root position at reset [m]
    start_rot: wp.quat  # root orientation at reset (xyzw)
    forward_dir: wp.vec3  # unit horizontal vector from the start towards the target: what forward means
    angular_velocity_scale: float
    dof_velocity_scale: float
    dof_force_scale: float
    contact_force_scale: float
    observe_dof_forces: int  # 1: joint forces are part of the observation (Humanoid)
    heading_weight: float
    up_weight: float
    alive_reward: float
    actions_cost: float
    energy_cost: float
    joints_at_limit_cost: float
    joint_limit_threshold: float
    scaled_limit_cost: int  # 0: count dofs above the threshold (Ant); 1: graded, both sides (Humanoid)
    death_cost: float
    termination_height: float
    episode_length: int
    dof_pos_noise: float
    dof_vel_noise: float
    max_speed: float  # any root or joint velocity above this [m/s, rad/s] means the solver diverged
