"""Isaac Gym's Ant (IsaacGymEnvs cfg/task/Ant.yaml): observation 60, action 8.

The physics differs from Isaac Gym's 2 substeps: with 2 MuJoCo substeps per 1/60 s step PPO learns
gaits that gain speed from the contact's penetration at that step size and lose a third of it at a
finer step. 3 substeps of 4 solver iterations hold up under 4x finer steps and in native MuJoCo
(docs/tasks.md, "Physics settings").
"""

from warpgym.physics import Physics
from warpgym.tasks.locomotion import LocomotionTask

ANT = LocomotionTask(
    name="Ant",
    robot="ant",
    substeps=3,
    physics=Physics(solver_iterations=4, ls_iterations=4),
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
