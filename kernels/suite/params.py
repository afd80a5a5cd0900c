"""What the kernels of Gymnasium's MuJoCo tasks read: the task's numbers (``GymParams``, filled by
``warpgym.tasks.suite``), MuJoCo Warp's arrays they take them from (``MjView``) and what a step
writes (``GymEpisodes``; ``kernels.common.StepOutputs`` for the returned tensors), and each kind's reward
terms, named once (``TERMS``: the step kernel writes each at its column by name, Gymnasium's info keys read them);
``SuiteState``, what a task's own terms beside Gymnasium's read.

Shapes: N worlds, Q = nq, V = nv, U = nu, B bodies (the world body 0 included), S sites, K reward
terms of the task, O observation entries.
"""

import enum

import warp as wp

# What a task's step computes (GymParams.kind): one code path per family of Gymnasium's step().
FORWARD = 0  # HalfCheetah, Hopper, Walker2d, Swimmer, Ant, Humanoid: forward speed, health, costs
STANDUP = 1  # HumanoidStandup: height over the timestep
PENDULUM = 2  # InvertedPendulum
DOUBLE_PENDULUM = 3  # InvertedDoublePendulum
REACHER = 4
PUSHER = 5



class ForwardTerm(enum.IntEnum):  # FORWARD's reward terms, each the column of GymEpisodes.terms it is written in
    reward_forward = 0
    reward_ctrl = 1
    reward_survive = 2
    reward_contact = 3
    x_velocity = 4
    y_velocity = 5
    x_position = 6


class StandupTerm(enum.IntEnum):
    reward_linup = 0
    reward_quadctrl = 1
    reward_impact = 2
    x_position = 3
    y_position = 4


class PendulumTerm(enum.IntEnum):
    reward_survive = 0


class DoublePendulumTerm(enum.IntEnum):
    reward_survive = 0
    distance_penalty = 1
    velocity_penalty = 2


class ReacherTerm(enum.IntEnum):
    reward_dist = 0
    reward_ctrl = 1


class PusherTerm(enum.IntEnum):
    reward_dist = 0
    reward_ctrl = 1
    reward_near = 2


TERMS = {FORWARD: ForwardTerm, STANDUP: StandupTerm, PENDULUM: PendulumTerm, DOUBLE_PENDULUM: DoublePendulumTerm,
         REACHER: ReacherTerm, PUSHER: PusherTerm}
MAX_TERMS = max(len(t) for t in TERMS.values())

# Where the forward speed comes from (GymParams.position_source): Gymnasium reads it differently per task.
POSITION_QPOS_X = 0  # qpos[0] (HalfCheetah, Hopper, Walker2d)
POSITION_QPOS_XY = 1  # qpos[0:2] (Swimmer)
POSITION_BODY = 2  # xpos of main_body (Ant)
POSITION_MASS_CENTER = 3  # mass-weighted xipos of all bodies (Humanoid)

# How contact forces are charged (GymParams.contact_cost_mode)
CONTACT_NONE = 0
CONTACT_CLIPPED_FORCES = 1  # weight * sum(clip(cfrc_ext, lo, hi)^2) (Ant)
CONTACT_CLIPPED_COST = 2  # clip(weight * sum(cfrc_ext^2), lo, hi) (Humanoid, HumanoidStandup)

# Reset targets drawn by rejection sampling (GymParams.goal_mode)
GOAL_NONE = 0
GOAL_REACHER = 1  # qpos[-2:] uniform in the 0.2 disc
GOAL_PUSHER = 2  # the cylinder's qpos[-4:-2] at least 0.17 from the goal at the origin

vec10 = wp.types.vector(length=10, dtype=float)  # MuJoCo's cinert: 6 inertia, 3 mass * com, mass


@wp.struct
class GymParams:
    kind: int
    dt: float  # control step: frame_skip * timestep [s]
    timestep: float  # MuJoCo's timestep [s]
    episode_length: int  # Gymnasium's TimeLimit
    # observation
    qpos_skip: int  # leading qpos entries left out (exclude_current_positions_from_observation)
    qvel_clip: float  # |qvel| in the observation clipped to this (inf: not clipped)
    obs_cinert: int
    obs_cvel: int
    obs_qfrc_actuator: int
    obs_cfrc_ext: int
    cfrc_lo: float  # cfrc_ext in the observation clipped to [lo, hi] (Ant's contact_force_range)
    cfrc_hi: float
    # reward
    position_source: int
    main_body: int
    forward_reward_weight: float
    ctrl_cost_weight: float
    contact_cost_mode: int
    contact_cost_weight: float
    contact_lo: float
    contact_hi: float
    healthy_reward: float
    terminate_when_unhealthy: int
    healthy_z_index: int  # qpos index of the height checked (-1: none)
    healthy_z_lo: float
    healthy_z_hi: float
    healthy_z_inclusive: int  # Ant checks lo <= z <= hi, the others lo < z < hi
    healthy_angle_index: int  # qpos index of the angle checked (-1: none)
    healthy_angle_lo: float
    healthy_angle_hi: float
    healthy_state_lo: float  # Hopper: every entry of state_vector()[2:] inside (lo, hi)
    healthy_state_hi: float
    healthy_finite: int  # Ant: the state must be finite
    # the manipulation and pendulum tasks
    body_a: int  # Reacher: fingertip; Pusher: tips_arm
    body_b: int  # Reacher: target; Pusher: object
    body_c: int  # Pusher: goal
    near_weight: float  # Pusher's reward_near_weight
    dist_weight: float  # reward_dist_weight
    # reset
    qpos_noise: float  # qpos = qpos0 + U(-qpos_noise, qpos_noise)
    qvel_noise: float  # qvel = U(-qvel_noise, qvel_noise), or qvel_noise * N(0, 1) with qvel_noise_normal
    qvel_noise_normal: int
    goal_mode: int


@wp.struct
class MjView:
    """MuJoCo Warp's ``Data`` (and the model constants a step reads), one row per world."""

    qpos: wp.array2d[float]  # (N, Q)
    qvel: wp.array2d[float]  # (N, V)
    ctrl: wp.array2d[float]  # (N, U)
    xpos: wp.array2d[wp.vec3]  # (N, B) body frames, as the last physics step computed them
    xipos: wp.array2d[wp.vec3]  # (N, B) body centres of mass
    cinert: wp.array2d[vec10]  # (N, B)
    cvel: wp.array2d[wp.spatial_vector]  # (N, B)
    cfrc_ext: wp.array2d[wp.spatial_vector]  # (N, B) after rne_postconstraint
    qfrc_actuator: wp.array2d[float]  # (N, V)
    qfrc_constraint: wp.array2d[float]  # (N, V)
    site_xpos: wp.array2d[wp.vec3]  # (N, S)
    warm_start: wp.array2d[float]  # (N, V) qacc_warmstart
    body_mass: wp.array[float]  # (B,)
    qpos0: wp.array[float]  # (Q,) Gymnasium's init_qpos
    total_mass: float


@wp.struct
class GymEpisodes:
    """Per-world accumulators of the running episode and the statistics of the one that just ended."""

    before: wp.array2d[float]  # (N, 2) the position the next step's forward speed is measured from
    length: wp.array[wp.int32]  # (N,)
    total_return: wp.array[float]  # (N,)
    travel: wp.array[float]  # (N,) forward distance of the episode so far [m]
    speed: wp.array[float]  # (N,) its forward speed [m/s] (0 for tasks without one)
    ended_return: wp.array[float]  # (N,)
    ended_length: wp.array[wp.int32]  # (N,)
    ended_speed: wp.array[float]  # (N,)
    terms: wp.array2d[float]  # (N, K) this step's reward terms and info, Gymnasium's keys in task order
    actions: wp.array2d[float]  # (N, U) this step's actions as given (NaN entries as 0)
    extra: wp.array2d[float]  # (N, E) this step's value of each of the task's own reward terms (a user's)


@wp.struct
class SuiteState:
    """What a term of a suite task reads (``(env: SuiteState, w: int[, params]) -> float``): the task's numbers,
    MuJoCo Warp's data as Gymnasium's step reads it, the episode's accumulators (``env.ep.actions``: the actions
    the control cost is charged on)."""

    p: GymParams
    d: MjView
    ep: GymEpisodes
