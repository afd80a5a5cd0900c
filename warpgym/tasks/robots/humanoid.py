"""Isaac Gym's Humanoid (IsaacGymEnvs cfg/task/Humanoid.yaml): observation 108, action 21.

The physics differs from Isaac Gym's in three ways, chosen from 10-minute runs of two seeds replayed at a
4x finer step (docs/history.md, "Physics settings: the investigation"):
- 3 substeps of 8 solver iterations per 1/60 s step (1/180 s, the timestep nv_humanoid.xml declares),
  against Isaac Gym's 2: at 2 substeps PPO finds, within 3 minutes, gaits that draw speed from the step;
- motors that slow with speed (``motor_speed=25``: torque falls to 0 at 25 rad/s at the full command, a
  DC motor's back-EMF): without them one seed's gait swung hinges at 72-105 rad/s, where the explicit
  velocity-product forces of the integrator paid it kilowatts, and it fell at a finer step;
- a rotor on every hinge (``armature=0.1`` kg m^2, a geared motor's reflected inertia, the MJCF's is
  0.006-0.02): with the motor alone the other seed's gait still leaned on the step (0.73 at 10 minutes).
With all three, both seeds keep 0.96-1.03 of their speed at 4x finer at 1, 2, 5 and 10 minutes.
"""

from warpgym.sim.physics import Physics
from warpgym.tasks.robots.base import LocomotionTask

HUMANOID = LocomotionTask(
    name="Humanoid",
    robot="humanoid",
    substeps=3,
    physics=Physics(solver_iterations=8, ls_iterations=8, armature=0.1, motor_speed=25.0),
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
