"""Isaac Gym's Humanoid (IsaacGymEnvs cfg/task/Humanoid.yaml): observation 108, action 21.

The physics differs from Isaac Gym's in one way: 3 substeps of 8 solver iterations per 1/60 s step
(1/180 s, the timestep nv_humanoid.xml itself declares), against Isaac Gym's 2. At 2 substeps PPO finds,
within 3 minutes, gaits that draw speed from the integration step: a 200-second policy runs 8.8 m/s at
1/120 s and keeps 0.81 of that at a 4x finer step, in warpgym and in native MuJoCo alike. A 10-minute
policy trained at 1/180 s keeps 0.96 (1, 2 and 5 minutes: 0.98-1.00). The Ant's remedy, a heavier rotor
on every hinge, made the Humanoid worse (armature 0.1: 0.62 after 3 minutes). docs/tasks.md, "Physics
settings", holds the measurements.
"""

from warpgym.sim.physics import Physics
from warpgym.tasks.locomotion import LocomotionTask

HUMANOID = LocomotionTask(
    name="Humanoid",
    robot="humanoid",
    substeps=3,
    physics=Physics(solver_iterations=8, ls_iterations=8),
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
