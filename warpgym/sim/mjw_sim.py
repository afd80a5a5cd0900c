"""``MjwSim``: N worlds of one MuJoCo model, as MuJoCo compiled its file, stepped by MuJoCo Warp.

Gymnasium's MuJoCo tasks run here rather than through Newton (``warpgym.sim.Sim``): Newton's
``add_mjcf`` rebuilds a model from the file and does not reproduce MuJoCo's compile of it (it
replaces HalfCheetah's Euler integrator by implicitfast, ignores ``settotalmass`` and rejects
``solver="PGS"``), while ``mujoco_warp.put_model`` takes MuJoCo's own ``MjModel``, so the physics
is the file's by construction (``warpgym.sim.gym_model``; tests/test_suite.py compares them field
by field).

Every buffer is MuJoCo Warp's ``Data``, allocated once; torch views of it stay valid for the life of
the sim. A control step is ``frame_skip`` calls of ``mujoco_warp.step`` captured as one graph.
"""

from __future__ import annotations

import time

import numpy as np
import torch
import warp as wp

from kernels.solver_load import track_solver_load
from warpgym.compile.preload import compile_ahead
from warpgym.sim.checks import check_env_ids, check_float_tensor, check_positive_int, solver_overflow_bits
from warpgym.sim.device import resolve_device
from warpgym.sim.gym_model import CompiledModel, compile_model
from warpgym.sim.mjw_internals import mujoco_contact_frames
from warpgym.sim.streams import CapturedLaunches, StreamOrder


class MjwSim(CapturedLaunches):
    """Batched MuJoCo Warp simulation of ``num_envs`` worlds of one model file.

    Args:
        model: a model file name in gymnasium's assets (e.g. "hopper.xml"), a path, or a ``CompiledModel``.
        num_envs: worlds.
        device: "cpu", "cuda" or "cuda:N"; default: cuda:0 when present, else cpu.
        frame_skip: physics steps per control step.
        nconmax, njmax: contacts and constraint rows per world MuJoCo Warp makes room for; a world that
            needs more loses the rest for that step (counted in ``solver_overflows``).
        contact_forces: compute ``cfrc_ext`` after the last physics step (``mj_rnePostConstraint``).
        contact_sensor_maxmatch: contacts a contact sensor considers (MuJoCo Warp's option of that name).

    ``after_substep``, when set, launches its work after each physics step of a control step (inside the graph).
    """

    def __init__(self, model: str | CompiledModel, num_envs: int = 1, device: str | None = None,
                 frame_skip: int = 1, nconmax: int = 32, njmax: int = 128, contact_forces: bool = False,
                 contact_sensor_maxmatch: int | None = None):
        import mujoco  # noqa: PLC0415
        import mujoco_warp as mjw  # noqa: PLC0415

        self.compiled = model if isinstance(model, CompiledModel) else compile_model(model)
        self.mjm = mjm = self.compiled.mjm
        self.num_envs = check_positive_int("num_envs", num_envs, "pass num_envs >= 1")
        self.frame_skip = check_positive_int("frame_skip", frame_skip, "pass frame_skip >= 1 (the task's, e.g. 5)")
        self.nconmax = check_positive_int("nconmax", nconmax, "pass e.g. 32")
        self.njmax = check_positive_int("njmax", njmax, "pass e.g. 128")
        self.device = resolve_device(device)
        self.torch_device = torch.device(self.device)
        self.contact_forces = bool(contact_forces)
        self._order = StreamOrder(self.device)
        self._mjw = mjw
        start = time.perf_counter()
        with wp.ScopedDevice(self.device):
            try:
                self.m = mjw.put_model(mjm)
            except NotImplementedError as e:
                raise NotImplementedError(f"{self.compiled.path}: MuJoCo Warp cannot simulate this model ({e}); "
                                          "change that feature in a copy of the file and pass its path") from None
            self.d = mjw.make_data(mjm, nworld=self.num_envs, nconmax=self.nconmax, njmax=self.njmax)
        self.nq, self.nv, self.nu, self.nbody = mjm.nq, mjm.nv, mjm.nu, mjm.nbody
        self.timestep = float(mjm.opt.timestep)
        self.dt = self.timestep * self.frame_skip
        self.has_free_root = mjm.njnt > 0 and mjm.jnt_type[0] == mujoco.mjtJoint.mjJNT_FREE
        self.body_names = [mujoco.mj_id2name(mjm, mujoco.mjtObj.mjOBJ_BODY, b) or "" for b in range(mjm.nbody)]
        self.ctrl_range = np.asarray(mjm.actuator_ctrlrange, np.float32).copy()

        self._drop_bits, quiet = solver_overflow_bits()
        self.m.opt.warn_overflow = int(self.m.opt.warn_overflow) & quiet
        if contact_sensor_maxmatch is not None:
            self.m.opt.contact_sensor_maxmatch = check_positive_int(
                "contact_sensor_maxmatch", contact_sensor_maxmatch, "pass e.g. 64")
        self.after_substep = None
        n = self.num_envs
        self._peak_nefc = wp.zeros(n, dtype=wp.int32, device=self.device)
        self._peak_nacon = wp.zeros(1, dtype=wp.int32, device=self.device)
        self._overflowed = wp.zeros(n, dtype=wp.int32, device=self.device)
        self._graph = None
        self.compile_log = [("model", {"seconds": time.perf_counter() - start})]

    # ------------------------------------------------------------------ stepping
    def simulate(self, after_forward: bool = False) -> None:
        """One control step as plain launches: ``frame_skip`` physics steps (what the graph holds).

        ``after_forward``: the data hold a forward pass of the very state the step starts from (``forward`` ran
        since qpos and qvel last changed; only the controls are new), so the first physics step starts from its
        actuation stage (MuJoCo Warp's ``step2``, MuJoCo's ``mj_step2``): the positions' and velocities' stages,
        collisions and constraints included, are not computed twice. Nothing in them reads the controls, so the
        step is the same."""
        mjw, m, d = self._mjw, self.m, self.d
        with wp.ScopedDevice(self.device), mujoco_contact_frames():
            for i in range(self.frame_skip):
                if i == 0 and after_forward:
                    mjw.step2(m, d)
                else:
                    mjw.step(m, d)
                wp.launch(track_solver_load, dim=self.num_envs,
                          inputs=[d.nefc, d.nacon, self._drop_bits, int(i == 0)],
                          outputs=[d.overflow, self._peak_nefc, self._peak_nacon, self._overflowed])
                if self.after_substep is not None:
                    self.after_substep()
            if self.contact_forces:
                mjw.rne_postconstraint(m, d)

    def forward(self) -> None:
        """MuJoCo's forward pass of every world's current state (``mj_forward``): body frames, velocities,
        contacts, constraint forces and sensors; and the factor of the inertia matrix, which MuJoCo Warp's forward
        pass solves with but does not keep (its fused factor-and-solve) and a step that starts from this pass
        (``simulate(after_forward=True)``) solves with again."""
        with wp.ScopedDevice(self.device), mujoco_contact_frames():
            self._mjw.forward(self.m, self.d)
            self._mjw.factor_m(self.m, self.d)

    def per_world(self, *fields: str) -> None:
        """Give each world its own copy of these model fields (MuJoCo Warp reads a model field's row
        ``world % rows``), so that kernels can write a value per world: domain randomisation."""
        with wp.ScopedDevice(self.device):
            for name in fields:
                arr = getattr(self.m, name)
                if arr.shape[0] == self.num_envs:
                    continue
                if arr.shape[0] != 1:
                    raise ValueError(f"model field {name} has {arr.shape[0]} rows: neither shared nor one per world")
                tiled = arr.numpy().repeat(self.num_envs, axis=0)
                setattr(self.m, name, wp.array(tiled, dtype=arr.dtype, device=self.device))
        self._graph = None

    def set_const(self) -> None:
        """Recompute the model constants derived from fields a kernel changed (MuJoCo Warp's ``set_const``:
        subtree masses, inverse weights, actuator accelerations), per world."""
        with wp.ScopedDevice(self.device):
            self._mjw.set_const(self.m, self.d)

    def kinematics(self, com: bool) -> None:
        """Body poses of the current qpos (``mj_kinematics``) and, with ``com``, com inertias and
        velocities (``mj_comPos``, ``mj_comVel``): what ``mj_forward`` gives an observation after a reset."""
        mjw, m, d = self._mjw, self.m, self.d
        with wp.ScopedDevice(self.device):
            mjw.kinematics(m, d)
            if com:
                mjw.com_pos(m, d)
                mjw.com_vel(m, d)

    def compile_ahead(self, fn) -> None:
        """Compile every module ``fn``'s launches need side by side (``warpgym.compile.preload``)."""
        self.compile_log.append(("step", compile_ahead(fn)))

    # ------------------------------------------------------------------ solver load
    @property
    def solver_overflows(self) -> wp.array:
        """(N,) int32: physics steps of the last control step in which a world lost constraints or contacts."""
        return self._overflowed

    def solver_load(self) -> dict:
        """The most constraint rows of any world against ``njmax`` and the most contacts of all worlds in
        one physics step against ``naconmax``, since the sim was built. One host read."""
        peak = int(self._peak_nacon.numpy()[0])
        return {"njmax": int(self.d.njmax), "peak_constraints_per_world": int(self._peak_nefc.numpy().max()),
                "naconmax": int(self.d.naconmax), "peak_contacts": peak,
                "peak_contacts_per_world_mean": peak / self.num_envs}

    # ------------------------------------------------------------------ Tensor API (MuJoCo's layout)
    def to_torch(self, array: wp.array) -> torch.Tensor:
        return wp.to_torch(array, requires_grad=False)

    @property
    def dof_pos(self) -> torch.Tensor:
        """(N, nq) MuJoCo's qpos of every world: a writable view (``set_state`` clears the solver's warm start)."""
        return self.to_torch(self.d.qpos)

    @property
    def dof_vel(self) -> torch.Tensor:
        """(N, nv) MuJoCo's qvel: a writable view."""
        return self.to_torch(self.d.qvel)

    @property
    def ctrl(self) -> torch.Tensor:
        """(N, nu) the controls of the next physics step (MuJoCo clamps them to ``ctrl_range``)."""
        return self.to_torch(self.d.ctrl)

    @property
    def dof_actuation_force(self) -> torch.Tensor:
        """(N, nv) MuJoCo's qfrc_actuator: the generalized force the actuators applied in the last physics step."""
        return self.to_torch(self.d.qfrc_actuator)

    def _root(self, what: str) -> None:
        if not self.has_free_root:
            raise AttributeError(f"{what}: {self.compiled.path} has no free root joint; use dof_pos / dof_vel")

    @property
    def root_pose(self) -> torch.Tensor:
        """(N, 7) position and quaternion (w, x, y, z: MuJoCo's order) of a free root joint; a view of qpos."""
        self._root("root_pose")
        return self.dof_pos[:, :7]

    @property
    def root_vel(self) -> torch.Tensor:
        """(N, 6) a free root's linear velocity (world frame) and angular velocity (body frame, as MuJoCo's
        qvel has it); a view of qvel."""
        self._root("root_vel")
        return self.dof_vel[:, :6]

    def set_state(self, qpos: torch.Tensor, qvel: torch.Tensor, env_ids: torch.Tensor | None = None) -> None:
        """Write qpos and qvel of the worlds ``env_ids`` (all when None) and forget their warm start."""
        ids = None
        if env_ids is not None:
            ids = check_env_ids("env_ids", env_ids, self.torch_device, self.num_envs, check_range=True).long()
        rows = self.num_envs if ids is None else ids.numel()
        qpos = check_float_tensor("qpos", qpos, self.torch_device, [(rows, self.nq)])
        qvel = check_float_tensor("qvel", qvel, self.torch_device, [(rows, self.nv)])
        warm = self.to_torch(self.d.qacc_warmstart)
        if ids is None:
            self.dof_pos.copy_(qpos), self.dof_vel.copy_(qvel), warm.zero_()
        else:
            self.dof_pos[ids], self.dof_vel[ids], warm[ids] = qpos, qvel, 0.0
        if self.torch_device.type == "cuda":  # the writes are torch's; the forward pass runs on Warp's stream
            torch.cuda.synchronize(self.torch_device)
        self.forward()  # frames, contacts and sensors of the state written (a step may start from them)

    def __repr__(self) -> str:
        return (f"MjwSim({self.compiled.path.rsplit('/', 1)[-1]!r}, num_envs={self.num_envs}, device={self.device!r}, "
                f"dt={self.dt:.5g}, frame_skip={self.frame_skip})")

