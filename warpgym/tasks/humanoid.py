"""Isaac Gym's Humanoid (IsaacGymEnvs cfg/task/Humanoid.yaml): observation 108, action 21."""

from warpgym.tasks.locomotion import LocomotionTask

HUMANOID = LocomotionTask(
    name="Humanoid",
    robot="humanoid",
    angular_velocity_scale=0.25,
    dof_velocity_scale=0.1,
    dof_force_scale=0.01,
    contact_force_scale=0.01,
    alive_reward=2.0,
    actions_cost=0.01,
    energy_cost=0.05,
    joints_at_limit_cost=0.25,
    joint_limit_threshold=0.98,
    scaled_limit_cost=True,
    death_cost=-1.0,
    termination_height=0.8,
)
