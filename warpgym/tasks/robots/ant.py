"""Isaac Gym's Ant (IsaacGymEnvs cfg/task/Ant.yaml): observation 60, action 8.

The physics differs from Isaac Gym's in two ways, both for the same reason: with nv_ant.xml's joint
armature of 0.01 kg m^2 the 0.91 kg robot's 15 N m motors swing a leg faster than MuJoCo's step can
follow, and PPO learns gaits that gain speed and height from the integration error (a policy that
runs 21 m/s with its torso at 1.5 m at 1/180 s runs 9.6 m/s at 1/720 s). The joints here carry an
armature of 0.1 kg m^2: about the reflected rotor inertia of a small motor behind a 100:1 gearbox
(1e-5 kg m^2 x 100^2), and the torque-to-armature ratio of Gymnasium's MuJoCo Ant (gear 150,
armature 1). The physics takes 4 substeps of 4 solver iterations per 1/60 s step (1/240 s), against
Isaac Gym's 2: at 3 substeps a 10-minute policy kept only 0.91 of its speed at a 4x finer step (0.95 at
5 minutes), at 4 substeps 10-minute policies of two seeds keep 0.97-1.01. docs/tasks.md, "Physics
settings", holds the measurements.
"""

from warpgym.sim.physics import Physics
from warpgym.tasks.robots.base import LocomotionTask

ANT = LocomotionTask(
    name="Ant",
    robot="ant",
    substeps=4,
    physics=Physics(solver_iterations=4, ls_iterations=4, armature=0.1),
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
