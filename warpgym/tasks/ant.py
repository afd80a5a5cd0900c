"""Isaac Gym's Ant (IsaacGymEnvs cfg/task/Ant.yaml): observation 60, action 8."""

from warpgym.tasks.locomotion import LocomotionTask

ANT = LocomotionTask(
    name="Ant",
    robot="ant",
    angular_velocity_scale=1.0,
    dof_velocity_scale=0.2,
    contact_force_scale=0.1,
    alive_reward=0.5,
    actions_cost=0.005,
    energy_cost=0.05,
    joints_at_limit_cost=0.1,
    joint_limit_threshold=0.99,
    scaled_limit_cost=False,
    death_cost=-2.0,
    termination_height=0.31,
)
