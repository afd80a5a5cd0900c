"""A legged velocity policy replayed in native MuJoCo (the scene file compiled by MuJoCo, stepped by ``mj_step`` in
float64 on the CPU) beside the same episodes in warpgym's env, over a fixed schedule of commands: the sim-to-sim
check of ``warpgym eval`` for the legged tasks.

Both sides play the nominal robot (no randomisation, no pushes, no observation noise, no encoder bias), from the
same starts (the keyframe pose turned to a yaw of its own per episode), the same commands (each held
``hold`` seconds, in turn), for the task's episode length. Tracking errors are mjlab's: the base's planar speed and
yaw rate against the command, from the base's own velocity in its frame, averaged over every step. A fall is what
ends the task's episode: the base tilted past the task's limit, or (the rough Go1) a thigh on the ground.

On rough ground the episodes start on the patches of one level, a kind of ground each in turn, and native MuJoCo's
observation casts the height scan with ``mj_ray`` (float64) as mjlab's sensor aims it; falls are counted per kind.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from warpgym.tasks.legged import LeggedTask
from warpgym.tasks.legged.model import compile_task_scene, resolve
from warpgym.tasks.terms import of_mode

# vx, vy [m/s], yaw rate [rad/s]: forward, a turn while walking, sideways, backward, turning in place, standing
SCHEDULE = ((1.0, 0.0, 0.0), (0.6, 0.0, 0.4), (0.0, 0.5, 0.0), (-0.6, 0.0, 0.0), (0.0, 0.0, -0.5), (0.0, 0.0, 0.0))
HOLD = 3.0  # seconds each command is held


@dataclass
class Tracking:
    error_xy: float  # mean |command - velocity| in the base's plane [m/s]
    error_yaw: float  # mean |command - yaw rate| [rad/s]
    falls: int
    episodes: int
    falls_by_kind: dict | None = None  # rough ground: {kind of ground: (falls, episodes)}
    errors_by_kind: dict | None = None  # rough ground: {kind of ground: (error xy, error yaw)}, the same means

    def to_dict(self) -> dict:
        return dict(vars(self))


def start_patches(ground, episodes: int, level: int) -> list[tuple[int, np.ndarray]]:
    """Episode e's kind of ground (e modulo the kinds) and its patch's start at ``level``: [(kind, origin)]."""
    level = min(level, ground.grid.num_rows - 1)
    cols = ground.grid.cols
    return [(e % cols, ground.origins[level, e % cols].astype(np.float64)) for e in range(episodes)]


def tracking(sums: np.ndarray, steps: np.ndarray, fell: list[bool], ground=None, kinds: list[int] | None = None
             ) -> Tracking:
    """Tracking errors from each episode's ``sums`` (episodes, 2) of per-step errors (xy, yaw) over its ``steps``
    counted: the means over every step of every episode and, on rough ground, over each kind's (``kinds``: each
    episode's kind of ground), with the falls per kind."""
    sums, steps = np.asarray(sums, np.float64), np.asarray(steps, np.float64)
    xy, yaw = sums.sum(0) / max(steps.sum(), 1.0)
    out = Tracking(float(xy), float(yaw), int(sum(fell)), len(fell))
    if ground is not None:
        names = [name for name, _ in ground.grid.sub_terrains]
        mine = {k: np.asarray(kinds) == k for k in sorted(set(kinds))}
        out.falls_by_kind = {names[k]: (int(sum(np.asarray(fell)[m])), int(m.sum())) for k, m in mine.items()}
        out.errors_by_kind = {names[k]: tuple(float(x) for x in sums[m].sum(0) / max(steps[m].sum(), 1.0))
                              for k, m in mine.items()}
    return out


def yaw_rotation(mat) -> np.ndarray:
    """mjlab's yaw-only rotation of a frame (3 x 3, float64): its x axis on the ground plane; nose straight up or
    down, its y axis turned a quarter to the right (kernels.legged.scan.yaw_rotation, in float32)."""
    mat = np.asarray(mat, np.float64).reshape(3, 3)
    x = mat[:2, 0]
    if np.linalg.norm(x) < 0.1:
        y = mat[:2, 1] / max(np.linalg.norm(mat[:2, 1]), 1e-6)
        x = np.array([y[1], -y[0]])
    x = x / max(np.linalg.norm(x), 1e-6)
    return np.array([[x[0], -x[1], 0.0], [x[1], x[0], 0.0], [0.0, 0.0, 1.0]])


def height_scan(mujoco, m, d, body: int, pattern) -> np.ndarray:
    """mjlab's height scan in native MuJoCo: the body's height above each ray's hit (``mj_ray`` over the pattern's
    geom groups, the body itself left out), aimed in the body's heading; the reach where nothing is hit."""
    rot = yaw_rotation(d.xmat[body])
    groups = np.array([1 if g in pattern.groups else 0 for g in range(6)], np.uint8)
    direction = rot @ np.asarray(pattern.direction, np.float64)
    pos = d.xpos[body]
    out = np.full(len(pattern.offsets), pattern.max_distance)
    geomid = np.zeros(1, np.int32)
    for i, offset in enumerate(pattern.array().astype(np.float64)):
        pnt = pos + rot @ offset
        dist = mujoco.mj_ray(m, d, pnt, direction, groups, 1, body, geomid)
        if 0 <= dist <= pattern.max_distance:
            out[i] = pos[2] - (pnt[2] + direction[2] * dist)
    return out


def commands(steps: int, dt: float, schedule=SCHEDULE, hold: float = HOLD) -> np.ndarray:
    """The command of every control step, (steps, 3)."""
    per = max(1, round(hold / dt))
    return np.array([schedule[(t // per) % len(schedule)] for t in range(steps)], np.float32)


def start_yaws(episodes: int) -> np.ndarray:
    return np.array([2 * math.pi * e / episodes - math.pi for e in range(episodes)])


def start_pose(idx, yaw: float) -> np.ndarray:
    """The keyframe pose turned to ``yaw``."""
    q = idx.default_root.astype(np.float64)
    c, s = math.cos(0.5 * yaw), math.sin(0.5 * yaw)
    w, x, y, z = q[3:7]
    turned = [w * c - z * s, x * c + y * s, y * c - x * s, w * s + z * c]
    return np.concatenate([q[:3], turned])


def base_velocity(quat, lin_world, ang_body):
    """The base's velocity in its own frame: the free joint's qvel holds the linear velocity in the world frame."""
    w, x, y, z = quat
    r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return r.T @ np.asarray(lin_world), np.asarray(ang_body)


def tilt(quat) -> float:
    """The angle between the base's z axis and the world's."""
    w, x, y, z = quat
    return math.acos(max(-1.0, min(1.0, 1 - 2 * (x * x + y * y))))


class PolicyView:
    """The policy's observation of a native MuJoCo state, written by the task's own table of terms: a one-world env
    on the CPU (nominal: no noise, bias or randomisation) whose MuJoCo data are copied from ``MjData`` (float64 to
    float32) and observed by the task's observation kernel, without a forward pass of its own. A user's own
    observation term is read in native MuJoCo as in warpgym."""

    FIELDS = ("qpos", "qvel", "xpos", "xquat", "cvel", "subtree_com", "site_xpos", "sensordata")

    def __init__(self, task: LeggedTask):
        from warpgym.envs.legged import LeggedVecEnv  # noqa: PLC0415  (the env above this layer, built on demand)

        self.env = LeggedVecEnv(task, num_envs=1, device="cpu", seed=0, events=of_mode(task.events, "reset"),
                                observation_noise=False)

    def __call__(self, d, action: np.ndarray, command: np.ndarray, scan: np.ndarray | None = None) -> np.ndarray:
        env = self.env
        for name in self.FIELDS:
            getattr(env.sim.d, name).assign(np.asarray(getattr(d, name), np.float32)[None])
        st = env._state
        st.action.assign(np.asarray(action, np.float32)[None])
        st.command.assign(np.asarray(command, np.float32)[None])
        if scan is not None:
            st.scan.assign(np.asarray(scan, np.float32)[None])
        env._launch_observe()
        return env.obs.numpy()[0].copy()

    def close(self) -> None:
        self.env.close()


def ends_episode(task: LeggedTask, idx, d, touched: bool) -> bool:
    """Whether the task's terminations (those that are no time-out) end an episode at native MuJoCo's state:
    the tilt past a termination's limit (``bad_orientation``), an illegal contact felt in the step (``touched``)."""
    from kernels.legged.terminations import bad_orientation, illegal_contact  # noqa: PLC0415

    r = idx.root_qpos
    for name, term in task.terminations.items():
        if term.time_out:
            continue
        if term.func is bad_orientation:
            if tilt(d.qpos[r + 3:r + 7]) > dict(term.params)["limit_angle"]:
                return True
        elif term.func is illegal_contact:
            if touched:
                return True
        else:
            raise ValueError(f"{task.name}: terminations[{name!r}] ({term.func.key}) has no native MuJoCo "
                             "counterpart in warpgym.native.legged.ends_episode: add one there, or drop the term "
                             "for the replay")
    return False


def native_episodes(task: LeggedTask, act, episodes: int, level: int | None = None) -> Tracking:
    """``act``: a function from the policy's observation (numpy float32, (obs,)) to its action. ``level``: the rough
    ground's level the episodes start on (default: the curriculum's highest first level)."""
    level = task.max_init_terrain_level if level is None else level
    import mujoco  # noqa: PLC0415

    from kernels.legged.params import ILLEGAL_CONTACT  # noqa: PLC0415

    compiled, ground = compile_task_scene(task)
    m = compiled.mjm
    d = mujoco.MjData(m)
    idx = resolve(task, m)
    observe = PolicyView(task)
    steps, dt = task.episode_length, task.decimation * task.timestep
    schedule = commands(steps, dt)
    r, j = idx.root_qpos, idx.joint_qpos
    illegal = idx.hit_force[idx.hit_group == ILLEGAL_CONTACT]
    starts = start_patches(ground, episodes, level) if ground is not None else [(0, np.zeros(3))] * episodes
    fell = []
    sums, counted = np.zeros((episodes, 2)), np.zeros(episodes)  # each episode's error sums and steps
    for e, (yaw, (_, origin)) in enumerate(zip(start_yaws(episodes), starts)):
        mujoco.mj_resetData(m, d)
        d.qpos[r:r + 7] = start_pose(idx, yaw)
        d.qpos[r:r + 3] += origin
        d.qpos[j] = idx.default_joint_pos
        mujoco.mj_forward(m, d)
        action = np.zeros(len(j), np.float32)
        ended = False
        for t in range(steps):
            cmd = schedule[t]
            scan = None if task.height_scan is None else height_scan(mujoco, m, d, idx.root_body, task.height_scan)
            action = np.asarray(act(observe(d, action, cmd, scan)), np.float32)
            d.ctrl[idx.joint_actuator] = action * idx.action_scale + idx.default_joint_pos
            touched = False
            for _ in range(task.decimation):
                mujoco.mj_step(m, d)
                touched |= any(np.linalg.norm(d.sensordata[a:a + 3]) > task.self_collision_force for a in illegal)
            mujoco.mj_forward(m, d)
            lin, ang = base_velocity(d.qpos[r + 3:r + 7], d.qvel[idx.root_dof:idx.root_dof + 3],
                                     d.qvel[idx.root_dof + 3:idx.root_dof + 6])
            sums[e] += (math.hypot(cmd[0] - lin[0], cmd[1] - lin[1]), abs(cmd[2] - ang[2]))
            counted[e] += 1
            if ends_episode(task, idx, d, touched):
                ended = True
                break
        fell.append(ended)
    observe.close()
    return tracking(sums, counted, fell, ground, [k for k, _ in starts])


def warpgym_episodes(task: LeggedTask, act, episodes: int, device: str = "cpu", level: int | None = None) -> Tracking:
    """The same episodes in warpgym's env, one world each; ``act`` maps a batch of observations (torch) to
    actions."""
    level = task.max_init_terrain_level if level is None else level
    import torch  # noqa: PLC0415

    from warpgym.envs.legged import LeggedVecEnv  # noqa: PLC0415

    env = LeggedVecEnv(task, num_envs=episodes, device=device, seed=0, events=of_mode(task.events, "reset"),
                       observation_noise=False, rel_standing_envs=0.0, rel_heading_envs=0.0, rel_forward_envs=0.0,
                       resampling_time=(1e6, 1e6))
    idx = env.index
    steps, dt = task.episode_length, task.decimation * task.timestep
    schedule = torch.as_tensor(commands(steps, dt), device=env.device)
    obs, _ = env.reset(seed=0)
    qpos = env.state()["qpos"]
    r = idx.root_qpos
    ground = env.terrain
    starts = start_patches(ground, episodes, level) if ground is not None else [(0, np.zeros(3))] * episodes
    for e, (yaw, (_, origin)) in enumerate(zip(start_yaws(episodes), starts)):
        qpos[e, r:r + 7] = torch.as_tensor(start_pose(idx, yaw))
        qpos[e, r:r + 3] += torch.as_tensor(origin, dtype=qpos.dtype)
        qpos[e, torch.as_tensor(idx.joint_qpos).long()] = torch.as_tensor(idx.default_joint_pos)
    start = {"qpos": qpos, "qvel": torch.zeros_like(env.state()["qvel"]), "command": schedule[0].expand(episodes, 3),
             "length": torch.zeros(episodes, dtype=torch.int32)}
    if ground is not None:
        level = min(level, ground.grid.num_rows - 1)
        start |= {"terrain_level": torch.full((episodes,), level, dtype=torch.int32),
                  "terrain_kind": torch.as_tensor([k for k, _ in starts], dtype=torch.int32),
                  "env_origin": torch.as_tensor(np.array([o for _, o in starts]), dtype=torch.float32)}
    env.write_state(start)
    obs, _ = env.observe()
    alive = torch.ones(episodes, dtype=torch.bool, device=env.device)
    root_dof = idx.root_dof
    sums = torch.zeros(episodes, 2, dtype=torch.float64, device=env.device)
    counted = torch.zeros(episodes, dtype=torch.long, device=env.device)  # device tensors: no host read per step
    falls = torch.zeros(episodes, dtype=torch.long, device=env.device)
    for t in range(steps):
        env.write_state({"command": schedule[t].expand(episodes, 3)})
        obs, reward, terminated, truncated, info = env.step(act(obs))
        q, v = env.sim.dof_pos, env.sim.dof_vel
        lin = rotate_to_base(q[:, r + 3:r + 7], v[:, root_dof:root_dof + 3])
        error_xy = torch.linalg.norm(schedule[t, :2] - lin[:, :2], dim=1)
        error_yaw = (schedule[t, 2] - v[:, root_dof + 5]).abs()
        sums += torch.stack([error_xy * alive, error_yaw * alive], dim=1).double()
        counted += alive
        falls += terminated & alive
        alive &= ~terminated
    env.close()
    return tracking(sums.cpu().numpy(), counted.cpu().numpy(), [bool(f) for f in falls.cpu()], ground,
                    [k for k, _ in starts])


def rotate_to_base(quat, lin_world):
    """World-frame vectors (N, 3) in the frames of unit quaternions (N, 4), (w, x, y, z): batched ``base_velocity``."""
    import torch  # noqa: PLC0415

    w, xyz = quat[:, :1], quat[:, 1:]
    t = 2.0 * torch.linalg.cross(xyz, lin_world)
    return lin_world - w * t + torch.linalg.cross(xyz, t)
