"""A warpgym robot in native MuJoCo (the ``mujoco`` package: C, CPU), loaded from the same MJCF.

A second simulator to check trained policies against (``warpgym sim2sim``) and the state mapping
that rendering needs. It imports neither Warp nor Newton: nothing here can inherit a mistake of
warpgym's own model import, which is the point of the check.

State in warpgym's layout (docs/tensor_api.md), ``K`` copies at a time:
    root_pose (K, 7)  body-origin position 3, quaternion xyzw 4
    root_vel (K, 6)   COM linear velocity 3, angular velocity 3, both world frame
    dof_pos, dof_vel (K, A) hinge joints in the MJCF's document order
MuJoCo's free joint stores the quaternion as wxyz, the body-origin linear velocity (world) and the
angular velocity in the body frame; ``set_state`` and ``state`` convert.

The scene differs from the file in one way, the same way warpgym's does: the file's floor (written
for Isaac Gym, Y-up in ``nv_ant.xml``) is replaced by a Z-up plane with Newton's ground-plane
contact settings, and the file's sensors (some name bodies that are not there) are dropped. A
stiffness that ``nv_humanoid.xml`` gives its free root joint through a default class is zeroed,
as Newton's import does.
"""

from __future__ import annotations

import numpy as np

from warpgym.sim.physics import Physics, exact_damping_scale, motor_damping
from warpgym.sim.robots import hinge_joint_names, mjcf_path, robot_spec
from warpgym.tasks.robots import LocomotionTask, get_task

# Newton's ground plane as MuJoCo Warp receives it (ShapeConfig defaults): friction, condim, margin.
GROUND_FRICTION = (1.0, 0.005, 0.0001)
INTEGRATORS = {"euler": 0, "implicit": 2, "implicitfast": 3}  # mjtIntegrator values


def _mujoco():
    try:
        import mujoco  # noqa: PLC0415
    except ImportError as e:  # pragma: no cover - mujoco comes with newton[sim]
        raise ImportError("native MuJoCo needs the 'mujoco' package: pip install mujoco") from e
    return mujoco


# ---------------------------------------------------------------- quaternions (xyzw, batched)
def quat_rotate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Rotate vectors v (..., 3) by unit quaternions q (..., 4) in xyzw order."""
    u, w = q[..., :3], q[..., 3:4]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def quat_rotate_inv(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    conj = np.concatenate([-q[..., :3], q[..., 3:4]], axis=-1)
    return quat_rotate(conj, v)


def xyzw_to_wxyz(q: np.ndarray) -> np.ndarray:
    return np.concatenate([q[..., 3:4], q[..., :3]], axis=-1)


def wxyz_to_xyzw(q: np.ndarray) -> np.ndarray:
    return np.concatenate([q[..., 1:4], q[..., 0:1]], axis=-1)


# ---------------------------------------------------------------- the model
def load_native_model(robot: str, timestep: float, physics: Physics | None = None, visual: bool = False):
    """The robot's MJCF compiled by MuJoCo itself, with warpgym's ground and physics settings.

    ``visual`` adds what only a camera sees (a checker floor, a sky, a light that follows no body):
    the same physics, dressed for ``warpgym.media.robots``."""
    physics = physics or Physics()
    if not (timestep > 0):
        raise ValueError(f"timestep={timestep!r} must be a positive number of seconds")
    mujoco = _mujoco()
    spec = mujoco.MjSpec.from_file(mjcf_path(robot_spec(robot)))
    for geom in list(spec.worldbody.geoms):
        if geom.type == mujoco.mjtGeom.mjGEOM_PLANE:
            spec.delete(geom)
    for sensor in list(spec.sensors):
        spec.delete(sensor)
    ground = spec.worldbody.add_geom(name="ground", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0.0, 0.0, 1.0],
                                     friction=list(GROUND_FRICTION), condim=3, margin=0.0)
    if visual:
        _dress_for_camera(mujoco, spec, ground)
    if physics.armature is not None:
        # On the spec, before compiling: the compiler derives the constraints' regularisation from the
        # mass matrix (dof_invweight0 and friends), armature included; a value written into the
        # compiled model afterwards would leave those at the MJCF's armature.
        for joint in spec.joints:
            if joint.type == mujoco.mjtJoint.mjJNT_HINGE:
                joint.armature = physics.armature
    model = spec.compile()
    # nv_humanoid.xml's default class gives every joint stiffness 5, its free root joint too: a spring
    # pulling the torso towards the origin, which Newton (and Isaac Gym) do not import.
    model.jnt_stiffness[model.jnt_type == mujoco.mjtJoint.mjJNT_FREE] = 0.0
    model.opt.timestep = timestep
    model.opt.integrator = INTEGRATORS[physics.integrator]
    model.opt.iterations = physics.solver_iterations
    model.opt.ls_iterations = physics.ls_iterations
    if physics.contact_timeconst is not None:
        model.geom_solref[:, 0] = physics.contact_timeconst
    if physics.motor_speed is not None:  # on the joint each motor drives, from MuJoCo's actuator table
        motors = model.actuator_trntype == mujoco.mjtTrn.mjTRN_JOINT
        dofs = model.jnt_dofadr[model.actuator_trnid[motors, 0]]
        model.dof_damping[dofs] += motor_damping(model.actuator_gear[motors, 0], physics.motor_speed)
    if physics.exact_damping:
        dofs, scale = exact_damping_scale(mujoco, model, timestep)
        model.dof_damping[dofs] *= scale
    return model


def _dress_for_camera(mujoco, spec, ground) -> None:
    """A 1 m checker floor (speed reads off it), a gradient sky and a fixed sun; offscreen buffers
    large enough for a 1920x1080 frame."""
    texture, builtin = mujoco.mjtTexture, mujoco.mjtBuiltin
    spec.add_texture(name="wg_sky", type=texture.mjTEXTURE_SKYBOX, builtin=builtin.mjBUILTIN_GRADIENT,
                     rgb1=[0.4, 0.6, 0.8], rgb2=[0.05, 0.05, 0.1], width=512, height=3072)
    spec.add_texture(name="wg_floor", type=texture.mjTEXTURE_2D, builtin=builtin.mjBUILTIN_CHECKER,
                     rgb1=[0.22, 0.3, 0.38], rgb2=[0.14, 0.19, 0.25], width=512, height=512,
                     mark=mujoco.mjtMark.mjMARK_EDGE, markrgb=[0.5, 0.55, 0.6])
    material = spec.add_material(name="wg_floor", texrepeat=[1.0, 1.0], texuniform=True, reflectance=0.0)
    material.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = "wg_floor"
    ground.material = "wg_floor"
    ground.rgba = [0.5, 0.5, 0.5, 1.0]  # MuJoCo's "unset" colour: the material's shows (the Ant's default is orange)
    spec.worldbody.add_light(name="wg_sun", type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL, pos=[0.0, 0.0, 10.0],
                             dir=[0.3, 0.4, -1.0], diffuse=[0.6, 0.6, 0.6], specular=[0.2, 0.2, 0.2], castshadow=False)
    spec.visual.global_.offwidth = max(spec.visual.global_.offwidth, 1920)
    spec.visual.global_.offheight = max(spec.visual.global_.offheight, 1080)
    spec.visual.map.zfar = max(spec.visual.map.zfar, 60.0)


class NativeRobot:
    """``copies`` independent copies of a task's robot in native MuJoCo, stepped one after another.

    Args:
        task: "Ant", "Humanoid" or a ``LocomotionTask`` (its robot, control step and observation).
        substeps: physics steps per control step (default: the task's).
        copies: how many robots (each its own ``MjData``).
        physics: a ``Physics`` or dict of its fields (default: the task's), applied as ``Sim`` applies it.
        visual: dress the scene for a camera (``load_native_model``); the physics is the same.
    """

    def __init__(self, task: str | LocomotionTask = "Ant", substeps: int | None = None, copies: int = 1,
                 physics: Physics | dict | None = None, visual: bool = False):
        mujoco = self._mj = _mujoco()
        self.task = get_task(task)
        self.spec = robot_spec(self.task.robot)
        self.substeps = int(substeps or self.task.substeps)
        if self.substeps < 1 or copies < 1:
            raise ValueError(f"substeps={substeps!r} and copies={copies!r} must be positive integers")
        if isinstance(physics, dict):
            physics = self.task.physics.replace(**physics)
        self.physics = physics or self.task.physics
        self.model = m = load_native_model(self.task.robot, self.task.dt / self.substeps, self.physics, visual)
        self.data = [mujoco.MjData(m) for _ in range(copies)]
        self.copies = copies

        names = hinge_joint_names(mjcf_path(self.spec))
        ids = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, n) for n in names]
        if min(ids) < 0:
            raise ValueError(f"{self.spec.mjcf}: joints {names} are not all in the compiled model")
        self.dof_names = names
        self.qpos_adr = m.jnt_qposadr[ids]
        self.dof_adr = m.jnt_dofadr[ids]
        self.dof_lower = m.jnt_range[ids, 0].astype(np.float64)
        self.dof_upper = m.jnt_range[ids, 1].astype(np.float64)
        self.default_dof_pos = np.clip(0.0, self.dof_lower, self.dof_upper)
        self.root_body = int(m.jnt_bodyid[0])
        if m.jnt_type[0] != mujoco.mjtJoint.mjJNT_FREE:
            raise ValueError(f"{self.spec.mjcf}: the first joint must be the free root joint")

        # Actions -> joint torques from MuJoCo's own actuator table (gear of the motor on each joint).
        gear = np.zeros(len(names))
        for a in range(m.nu):
            joint = int(m.actuator_trnid[a, 0])
            if joint in ids:
                gear[ids.index(joint)] = m.actuator_gear[a, 0]
        self.torque_scale = gear * self.task.power_scale
        self.effort_ratio = gear / gear.max()
        self.feet = np.array([mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, f) for f in self.spec.feet])
        if (self.feet < 0).any():
            raise ValueError(f"{self.spec.mjcf}: feet {self.spec.feet} are not all bodies of the model")
        self._foot_geom = np.isin(m.geom_bodyid, self.feet)
        # (K,) bool: some foot had a contact with the ground in some substep of the last step()
        self.feet_touched = np.zeros(copies, bool)
        # called after every substep of step() as on_substep(copy, data, qvel before the substep), for
        # measurements that need each substep (benchmarks/physics/step_sensitivity.py: the power of each force)
        self.on_substep = None

    # ------------------------------------------------------------------ state
    def set_state(self, root_pose, root_vel, dof_pos, dof_vel) -> None:
        """Write warpgym-layout states (one row per copy) and recompute everything that follows."""
        root_pose, root_vel = np.asarray(root_pose, np.float64), np.asarray(root_vel, np.float64)
        dof_pos, dof_vel = np.asarray(dof_pos, np.float64), np.asarray(dof_vel, np.float64)
        m = self.model
        for k, d in enumerate(self.data):
            q = root_pose[k, 3:7] / np.linalg.norm(root_pose[k, 3:7])
            d.qpos[:3] = root_pose[k, :3]
            d.qpos[3:7] = xyzw_to_wxyz(q)
            d.qpos[self.qpos_adr] = dof_pos[k]
            w_world = root_vel[k, 3:6]
            com_offset = quat_rotate(q, m.body_ipos[self.root_body])  # origin -> COM, world frame
            d.qvel[:3] = root_vel[k, :3] - np.cross(w_world, com_offset)
            d.qvel[3:6] = quat_rotate_inv(q, w_world)
            d.qvel[self.dof_adr] = dof_vel[k]
            d.qacc_warmstart[:] = 0.0
            self._mj.mj_forward(m, d)

    def state(self) -> dict[str, np.ndarray]:
        m = self.model
        pose = np.zeros((self.copies, 7))
        vel = np.zeros((self.copies, 6))
        for k, d in enumerate(self.data):
            q = wxyz_to_xyzw(d.qpos[3:7])
            pose[k, :3], pose[k, 3:] = d.qpos[:3], q
            w_world = quat_rotate(q, d.qvel[3:6])
            vel[k, :3] = d.qvel[:3] + np.cross(w_world, quat_rotate(q, m.body_ipos[self.root_body]))
            vel[k, 3:] = w_world
        return {"root_pose": pose, "root_vel": vel,
                "dof_pos": np.stack([d.qpos[self.qpos_adr] for d in self.data]),
                "dof_vel": np.stack([d.qvel[self.dof_adr] for d in self.data])}

    def reset(self, rng: np.random.Generator) -> None:
        """warpgym's reset distribution: upright at the start height, dofs at default plus uniform noise."""
        t, n, a = self.task, self.copies, len(self.dof_names)
        pose = np.zeros((n, 7))
        pose[:, 2], pose[:, 6] = self.spec.start_height, 1.0
        dof_pos = np.clip(self.default_dof_pos + rng.uniform(-t.dof_pos_noise, t.dof_pos_noise, (n, a)),
                          self.dof_lower, self.dof_upper)
        self.set_state(pose, np.zeros((n, 6)), dof_pos, rng.uniform(-t.dof_vel_noise, t.dof_vel_noise, (n, a)))

    # ------------------------------------------------------------------ stepping
    def step(self, actions: np.ndarray, active: np.ndarray | None = None) -> np.ndarray:
        """Apply actions (K, A) as warpgym does (non-finite -> 0, clipped to [-1, 1], times gear and
        power scale) for ``substeps`` physics steps. Copies where ``active`` is False stay put.
        Returns the applied actions."""
        mj = self._mj
        actions = np.nan_to_num(np.asarray(actions, np.float64), nan=0.0, posinf=0.0, neginf=0.0)
        actions = np.clip(actions, -1.0, 1.0)
        for k, d in enumerate(self.data):
            if active is not None and not active[k]:
                continue
            d.qfrc_applied[:] = 0.0
            d.qfrc_applied[self.dof_adr] = actions[k] * self.torque_scale
            touched = False
            for _ in range(self.substeps):
                before = d.qvel.copy() if self.on_substep is not None else None
                mj.mj_step(self.model, d)
                if self.physics.max_joint_speed is not None:
                    v = self.physics.max_joint_speed
                    d.qvel[self.dof_adr] = np.clip(d.qvel[self.dof_adr], -v, v)
                if self.on_substep is not None:
                    self.on_substep(k, d, before)
                # every substep, not just the last: a bounding gait's feet may touch down mid-step
                touched = touched or self._foot_on_ground(d)
            self.feet_touched[k] = touched
        return actions

    def _foot_on_ground(self, d) -> bool:
        """A contact (within the geoms' margin) between a foot geom and a geom of the world body."""
        if d.ncon == 0:
            return False
        geoms = d.contact.geom[: d.ncon]
        world = self.model.geom_bodyid[geoms] == 0
        foot = self._foot_geom[geoms]
        return bool(((foot[:, 0] & world[:, 1]) | (foot[:, 1] & world[:, 0])).any())

    # ------------------------------------------------------------------ sensing
    def contact_wrenches(self, bodies) -> np.ndarray:
        """(K, len(bodies), 6): contact force 3 and torque 3 about each body's origin, world frame,
        from the last physics step's constraint forces (what warpgym observes)."""
        mj = self._mj
        out = np.zeros((self.copies, len(bodies), 6))
        for k, d in enumerate(self.data):
            mj.mj_rnePostConstraint(self.model, d)
            for i, b in enumerate(bodies):
                torque, force = d.cfrc_ext[b, :3], d.cfrc_ext[b, 3:]
                arm = d.xpos[b] - d.subtree_com[self.model.body_rootid[b]]
                out[k, i, :3], out[k, i, 3:] = force, torque - np.cross(arm, force)
        return out

    def dof_forces(self) -> np.ndarray:
        """(K, A): actuation plus passive (spring, damping) force on each hinge, last physics step."""
        return np.stack([d.qfrc_applied[self.dof_adr] + d.qfrc_passive[self.dof_adr] for d in self.data])

    def feet_in_contact(self) -> np.ndarray:
        """(K, F) bool: the foot touched the ground (any contact force) in the last physics step."""
        return np.linalg.norm(self.contact_wrenches(self.feet)[..., :3], axis=-1) > 0.0

    def observation(self, actions: np.ndarray, fresh: bool = False) -> np.ndarray:
        """The task's observation (Isaac Gym's layout, ``kernels/robots/observations.py``) from MuJoCo's data."""
        s = self.state()
        feet = np.zeros((self.copies, len(self.feet), 6)) if fresh else self.contact_wrenches(self.feet)
        dof_force = None
        if self.task.observe_dof_forces:
            dof_force = np.zeros((self.copies, len(self.dof_names))) if fresh else self.dof_forces()
        return locomotion_observation(self.task, s, self.dof_lower, self.dof_upper, dof_force, feet,
                                      np.zeros_like(actions) if fresh else actions)


def locomotion_observation(task: LocomotionTask, s: dict, dof_lower, dof_upper, dof_force, foot_wrench,
                           actions) -> np.ndarray:
    """A numpy twin of ``write_observation`` for states in warpgym's layout (start rotation: identity)."""
    pos, q = s["root_pose"][:, :3], s["root_pose"][:, 3:7]
    lin, ang = s["root_vel"][:, :3], s["root_vel"][:, 3:6]
    n = pos.shape[0]
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    yaw = np.arctan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)
    roll = np.arctan2(2.0 * (w * x + y * z), w * w - x * x - y * y + z * z)
    target = np.asarray(task.target, np.float64)
    to_target = target[None, :] - pos
    to_target[:, 2] = 0.0
    up = quat_rotate(q, np.broadcast_to([0.0, 0.0, 1.0], (n, 3)))
    heading = quat_rotate(q, np.broadcast_to([1.0, 0.0, 0.0], (n, 3)))
    angle = np.arctan2(to_target[:, 1], to_target[:, 0]) - yaw
    direction = to_target / np.linalg.norm(to_target, axis=1, keepdims=True)
    parts = [
        pos[:, 2:3],
        quat_rotate_inv(q, lin),
        quat_rotate_inv(q, ang) * task.angular_velocity_scale,
        yaw[:, None],
        roll[:, None],
        np.arctan2(np.sin(angle), np.cos(angle))[:, None],
        up[:, 2:3],
        np.sum(heading * direction, axis=1, keepdims=True),
        (2.0 * s["dof_pos"] - dof_upper - dof_lower) / (dof_upper - dof_lower),
        s["dof_vel"] * task.dof_velocity_scale,
    ]
    if task.observe_dof_forces:
        parts.append(dof_force * task.dof_force_scale)
    parts.append(foot_wrench.reshape(n, -1) * task.contact_force_scale)
    parts.append(actions)
    return np.nan_to_num(np.concatenate(parts, axis=1), nan=0.0, posinf=0.0, neginf=0.0)


OBSERVATION_TERMS = ("height", "velocity", "angular_velocity", "yaw", "roll", "angle_to_target", "up",
                     "heading", "dof_pos", "dof_vel", "dof_force", "feet", "actions")


def observation_slices(task: LocomotionTask, num_dofs: int, num_feet: int) -> dict[str, slice]:
    """Name -> columns of each term of the locomotion observation."""
    sizes = [1, 3, 3, 1, 1, 1, 1, 1, num_dofs, num_dofs, num_dofs if task.observe_dof_forces else 0,
             6 * num_feet, num_dofs]
    out, col = {}, 0
    for name, size in zip(OBSERVATION_TERMS, sizes):
        if size:
            out[name] = slice(col, col + size)
        col += size
    return out
