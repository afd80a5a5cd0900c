"""What the legged velocity tasks' kernels read and write: the task's numbers (``LeggedParams``, filled by
``warpgym.tasks.legged``), the robot's indices in MuJoCo's model (``LeggedRobot``), MuJoCo Warp's data
(``MjLegged``) and the model fields randomised per world (``MjLeggedModel``), the per-world task state
(``LeggedState``: command, timers, contact times, action history, randomised encoder bias), the terrain curriculum
(``TerrainLevels``) and the episode bookkeeping (``LeggedEpisodes``). ``LeggedEnv`` holds all but the last: it is
what every term function reads (the contract a user's own reward, observation, termination or event is written
against, ``warpgym.tasks.terms``).

Shapes: N worlds, J actuated joints (hinges, in the model's order, which is the action's), F feet, G foot geoms,
K reward terms, S command stages (or height scan rays), H contact group sensors, Q = nq, V = nv, B bodies, T sites,
D sensor data entries.
"""

import warp as wp


# Contact groups (LeggedRobot.hit_group): each counts the physics steps of a control step in which any of its
# contact sensors felt more than ``LeggedParams.collision_force`` (mjlab's force history over the decimation)
SELF_COLLISION = 0  # the self_collisions term
SHANK_GROUND = 1  # the shank_collision term
TRUNK_GROUND = 2  # the trunk_head_collision term
ILLEGAL_CONTACT = 3  # ends the episode (mjlab's illegal_contact termination)
NUM_GROUPS = 4

# Command flags (LeggedState.command_kind): bits of one int per world
HEADING = 1  # the yaw rate steers toward a heading target
STANDING = 2  # the whole command is zero
FORWARD = 4  # forward only: x at least the forward minimum, no sideways or turning


@wp.struct
class LeggedParams:
    dt: float  # control step: decimation * timestep [s]
    physics_dt: float  # MuJoCo's timestep [s]
    episode_length: int  # control steps to the time limit
    # velocity command (mjlab's UniformVelocityCommand and its command curriculum)
    stage_steps: wp.array[wp.int32]  # (S,) env step from which stage s's ranges hold
    stage_ranges: wp.array2d[float]  # (S, 6) lin_x lo, hi, lin_y lo, hi, ang_z lo, hi
    heading_lo: float
    heading_hi: float
    resample_lo: float  # seconds between resamples, uniform in [lo, hi]
    resample_hi: float
    rel_standing: float
    rel_heading: float
    rel_forward: float
    heading_stiffness: float
    forward_min: float
    max_command_steps: float  # resample_hi / dt: the tracking errors' divisor
    collision_force: float  # contact force [N] above which a contact group's physics step counts
    foot_scan: int  # 1: the feet's heights are scanned (rough ground), else the sites' heights above z = 0


@wp.struct
class LeggedRobot:
    root_body: int
    upright_body: int  # whose tilt the upright reward scores
    angvel_body: int  # whose roll and pitch rates body_ang_vel charges
    com_body: int  # whose centre of mass the base_com event moves
    root_qpos: int  # qpos address of the free joint
    root_dof: int
    joint_qpos: wp.array[wp.int32]  # (J,)
    joint_dof: wp.array[wp.int32]  # (J,)
    default_root: wp.array[float]  # (7,) position, quaternion (w, x, y, z)
    default_joint_pos: wp.array[float]  # (J,)
    soft_lo: wp.array[float]  # (J,) soft joint limits
    soft_hi: wp.array[float]
    joint_actuator: wp.array[wp.int32]  # (J,) the actuator (control) of each joint
    action_scale: wp.array[float]  # (J,)
    foot_site: wp.array[wp.int32]  # (F,)
    foot_geom: wp.array[wp.int32]  # (G,) the feet's collision geoms (their friction is randomised)
    foot_body: wp.array[wp.int32]  # (F,) the body each foot's site is fixed to
    foot_found: wp.array[wp.int32]  # (F,) sensordata address of each foot's contact count
    foot_force: wp.array[wp.int32]  # (F,) ... of its net contact force (world frame)
    imu_lin_vel: int  # sensordata addresses (velocimeter, gyro, subtree angular momentum)
    imu_ang_vel: int
    angmom: int
    hit_force: wp.array[wp.int32]  # (H,) sensordata addresses of the contact groups' sensors' forces
    hit_group: wp.array[wp.int32]  # (H,) the group of each


@wp.struct
class MjLegged:
    """MuJoCo Warp's ``Data``, one row per world."""

    qpos: wp.array2d[float]  # (N, Q)
    qvel: wp.array2d[float]  # (N, V)
    ctrl: wp.array2d[float]  # (N, J) in the actuators' order
    xpos: wp.array2d[wp.vec3]  # (N, B)
    xquat: wp.array2d[wp.quat]  # (N, B) (w, x, y, z) as MuJoCo orders them
    cvel: wp.array2d[wp.spatial_vector]  # (N, B) (angular, linear) about the subtree's centre of mass
    subtree_com: wp.array2d[wp.vec3]  # (N, B)
    site_xpos: wp.array2d[wp.vec3]  # (N, T)
    sensordata: wp.array2d[float]  # (N, D)
    warm_start: wp.array2d[float]  # (N, V) qacc_warmstart


@wp.struct
class MjLeggedModel:
    """MuJoCo Warp's model fields that events change per world (one row a world), and their compiled values."""

    geom_friction: wp.array2d[wp.vec3]  # (N, G)
    body_ipos: wp.array2d[wp.vec3]  # (N, B) each body's centre of mass in its frame
    body_ipos0: wp.array[wp.vec3]  # (B,) the compiled model's


@wp.struct
class LeggedState:
    """What a world carries from step to step beside MuJoCo's state."""

    action: wp.array2d[float]  # (N, J) the last action (NaN entries as 0), one entry per joint
    prev_action: wp.array2d[float]  # (N, J)
    command: wp.array2d[float]  # (N, 3) vx, vy [m/s], yaw rate [rad/s] in the base's frame
    heading_target: wp.array[float]  # (N,)
    command_kind: wp.array[wp.int32]  # (N,) HEADING | STANDING | FORWARD
    command_time_left: wp.array[float]  # (N,) seconds to the next resample
    air_time: wp.array2d[float]  # (N, F) seconds each foot has been off the ground
    contact_time: wp.array2d[float]  # (N, F) ... on it
    peak_height: wp.array2d[float]  # (N, F) highest foot height of the swing in progress
    foot_height: wp.array2d[float]  # (N, F) foot heights when the last observation was made
    collision_hits: wp.array2d[wp.int32]  # (N, NUM_GROUPS) physics steps of this step with a contact of each group
    encoder_bias: wp.array2d[float]  # (N, J) randomised once per world (the encoder_bias event)
    scan: wp.array2d[float]  # (N, max(S, 1)) the height scan (unscaled, no noise) at the last observation
    foot_clear: wp.array2d[float]  # (N, F) the feet's scanned heights at the last observation (rough ground)
    terrain_normal: wp.array[wp.vec3]  # (N,) the ground's normal under the base at the last observation
    step_count: wp.array[wp.int32]  # (1,) env steps since the env was built (the command curriculum's clock)
    fresh: wp.array[wp.int32]  # (N,) 1 from a world's reset to its first observation (observation history)


@wp.struct
class LeggedEpisodes:
    length: wp.array[wp.int32]  # (N,)
    total_return: wp.array[float]  # (N,)
    errors: wp.array2d[float]  # (N, 2) mjlab's tracking errors so far: xy speed, yaw rate
    ended_return: wp.array[float]  # (N,)
    ended_length: wp.array[wp.int32]  # (N,)
    ended_errors: wp.array2d[float]  # (N, 2)
    terms: wp.array2d[float]  # (N, K) this step's weighted reward terms (their sum is the reward)


@wp.struct
class TerrainLevels:
    """mjlab's terrain curriculum on a grid whose rows are levels and whose columns are kinds of ground (L rows, C
    columns); on the flat floor one start at the origin and no bound."""

    origins: wp.array2d[wp.vec3]  # (L, C) each patch's start (world frame)
    level: wp.array[wp.int32]  # (N,) each world's row
    kind: wp.array[wp.int32]  # (N,) each world's column, fixed
    origin: wp.array[wp.vec3]  # (N,) each world's start: origins[level, kind]
    patch_length: float  # a patch's size along x [m]: half of it walked moves a world up
    episode_s: float  # the episode's length [s]
    half_x: float  # the ground's half extent, border included, less the bound's margin [m]
    half_y: float


@wp.struct
class LeggedEnv:
    """Everything a term function of a legged task reads: ``env.p`` the task's numbers, ``env.r`` the robot's
    indices, ``env.d`` MuJoCo Warp's data, ``env.m`` its model fields that events randomise, ``env.st`` the task's
    per-world state, ``env.t`` the terrain levels."""

    p: LeggedParams
    r: LeggedRobot
    d: MjLegged
    m: MjLeggedModel
    st: LeggedState
    t: TerrainLevels
