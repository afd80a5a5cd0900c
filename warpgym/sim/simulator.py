"""``Sim``: N copies of one robot on a ground plane, stepped by Newton's MuJoCo Warp solver.

Every buffer is allocated once. The Newton state is stepped in place (MuJoCo Warp reads
``joint_q``/``joint_qd`` at the start of a substep and writes them back at its end), so a torch view
taken of it stays valid for the life of the Sim. The substeps run as one captured graph: a CUDA
graph, or on the CPU Warp's recorded launch list.
"""

from __future__ import annotations

import math
import time

import numpy as np
import torch
import warp as wp

from kernels import tensor_api as k_api
from kernels.solver_load import track_solver_load
from warpgym.compile.preload import Preload, compile_ahead
from warpgym.sim import newton_internals
from warpgym.sim.checks import check_positive_int, solver_overflow_bits
from warpgym.sim.device import resolve_device
from warpgym.sim.physics import Physics, exact_damping_scale, motor_damping
from warpgym.sim.robots import RobotSpec, hinge_joint_names, mjcf_path, motor_gears, robot_spec
from warpgym.sim.streams import CapturedLaunches, StreamOrder
from warpgym.sim.tensor_api import TensorAPI


def _leaf(label: str) -> str:
    return label.rsplit("/", 1)[-1]


# Worlds in the model whose construction and first substep are rehearsed to name MuJoCo Warp's
# kernels: two, not one, so that nothing takes a single-world shortcut the real model would not.
REHEARSAL_WORLDS = 2


class _PhaseClock:
    """Seconds of each phase of a build, for the start-up timeline (``Sim.build_times``)."""

    def __init__(self):
        self.laps: dict[str, float] = {}
        self._last = time.perf_counter()

    def lap(self, phase: str) -> None:
        now = time.perf_counter()
        self.laps[phase] = self.laps.get(phase, 0.0) + now - self._last
        self._last = now


class Sim(TensorAPI, CapturedLaunches):
    """Batched rigid-body simulation of ``num_envs`` independent worlds of one robot.

    Args:
        robot: "ant" or "humanoid".
        num_envs: number of worlds (one robot each).
        device: "cpu", "cuda" or "cuda:N"; default: cuda:0 when present, else cpu.
        seed: seed for the tasks built on this Sim (the bare Sim itself draws no random numbers).
        dt: control step [s]; one ``step()`` advances this much.
        substeps: physics substeps per control step.
        physics: a ``Physics`` (or a dict of its fields): integrator, iteration caps, armature, joint
            speed clamp, contact time constant. Default: ``Physics()``.
        njmax, nconmax: constraint rows and contacts per world that MuJoCo Warp makes room for
            (default: the robot's, see ``warpgym/sim/robots.py``); a world that needs more loses the rest.
        check_inputs: validate index tensors on the host (one synchronisation per indexed set).
    """

    def __init__(
        self,
        robot: str = "ant",
        num_envs: int = 1,
        device: str | None = None,
        seed: int = 0,
        dt: float = 1.0 / 60.0,
        substeps: int = 2,
        physics: Physics | dict | None = None,
        njmax: int | None = None,
        nconmax: int | None = None,
        check_inputs: bool = True,
    ):
        self.spec: RobotSpec = robot_spec(robot)
        self.num_envs = check_positive_int("num_envs", num_envs, "pass num_envs >= 1")
        self.substeps = check_positive_int("substeps", substeps, "pass substeps >= 1 (2 is the default)")
        if not (isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt={dt!r} must be a positive number of seconds, e.g. 1/60")
        self.physics = physics if isinstance(physics, Physics) else Physics.from_dict(physics)
        self.njmax = self.spec.njmax if njmax is None else check_positive_int("njmax", njmax, "pass e.g. 128")
        self.nconmax = self.spec.nconmax if nconmax is None else check_positive_int("nconmax", nconmax, "pass e.g. 48")
        self.device = resolve_device(device)
        self.torch_device = torch.device(self.device)
        self.seed = int(seed)
        self.dt = float(dt)
        self.check_inputs = bool(check_inputs)
        self._order = StreamOrder(self.device)

        self._graph = None
        self._contact_forces = False
        # Convert Newton's state to MuJoCo's and back once per control step, not once per substep
        # (simulate()); False takes Newton's public step every substep (the reference in tests), as
        # does a Newton without the private phases this needs (newton_internals).
        self.convert_once_per_step = True
        self._tensors: dict[str, tuple[wp.array, torch.Tensor]] = {}
        self._build()

    # ------------------------------------------------------------------ model
    def _check_memory(self) -> None:
        if not self.device.startswith("cuda"):
            return
        free, _ = torch.cuda.mem_get_info(self.torch_device)
        need = self.spec.mib_per_1000_envs * self.num_envs / 1000 * 2**20
        if need > 0.9 * free:
            fits = int(0.9 * free / (self.spec.mib_per_1000_envs * 2**20) * 1000)
            raise MemoryError(
                f"num_envs={self.num_envs} {self.spec.name} worlds need about {need / 2**30:.1f} GiB on "
                f"{self.device}, which has {free / 2**30:.1f} GiB free: pass num_envs <= {fits}"
            )

    def _build(self) -> None:
        """Newton's model of ``num_envs`` robots and its MuJoCo Warp solver, with the kernels compiled side by
        side while it is built (warpgym.compile.preload); each phase's seconds go to ``build_times``."""
        clock = _PhaseClock()
        import newton  # noqa: PLC0415

        clock.lap("import Newton")
        self._check_memory()
        preload = Preload(self.device)  # compiles while the models are built below
        path = mjcf_path(self.spec)
        robot = newton.ModelBuilder()
        robot.add_mjcf(path, ignore_names=["floor", "ground"])

        def build_model(num_worlds: int):
            scene = newton.ModelBuilder()
            scene.add_ground_plane()
            scene.replicate(robot, num_worlds)
            return scene.finalize(device=self.device)

        self._solver_settings(path)
        start = time.perf_counter()
        queued, stopped_early = self._rehearse(preload, build_model)
        clock.lap("rehearsal")
        self.model = model = build_model(self.num_envs)
        clock.lap("model")
        self._read_layout(model, path)
        self._set_start_state(model)
        preload.wait()
        clock.lap("waiting for compiles")
        self.compile_log = [("solver", {"queued": queued, "seconds": time.perf_counter() - start,
                                        "stopped_early": repr(stopped_early) if stopped_early else None})]
        self.solver = self._make_solver(model)
        self.convert_once_per_step &= newton_internals.supports_split_substeps(self.solver)
        clock.lap("solver")
        self._make_state(model)

        # The kernels specialised to the world count, named by a launch-free step of this model
        # (contact forces on: tasks ask for them) and compiled side by side now, not at first launch.
        self._contact_forces = True
        self.compile_ahead(self.simulate)
        self._contact_forces = False
        clock.lap("step rehearsal")
        self.build_times = clock.laps

    def _solver_settings(self, path: str) -> None:
        """Which of MuJoCo Warp's overflow flags count as dropped constraints, which it may stop printing, and
        the motors' gears that motor damping is scaled by."""
        self._drop_bits, self._quiet_bits = solver_overflow_bits()
        self._gears_by_joint = motor_gears(path)
        self._hinge_gears = [self._gears_by_joint.get(name, 0.0) for name in hinge_joint_names(path)]

    def _make_solver(self, model):
        """Newton's MuJoCo solver for ``model`` with this Sim's physics settings applied to its model."""
        import newton  # noqa: PLC0415

        phys = self.physics
        solver = newton.solvers.SolverMuJoCo(
            model,
            iterations=phys.solver_iterations,
            ls_iterations=phys.ls_iterations,
            integrator=phys.integrator,
            nconmax=self.nconmax,
            njmax=self.njmax,
            disable_sensors=True,
        )
        if phys.contact_timeconst is not None:
            solref = solver.mjw_model.geom_solref.numpy()
            solref[..., 0] = phys.contact_timeconst
            solver.mjw_model.geom_solref.assign(solref)
        if phys.motor_speed is not None or phys.exact_damping:
            import mujoco  # noqa: PLC0415

            damping = solver.mjw_model.dof_damping.numpy()
            cpu = solver.mj_model  # the solver's CPU model, kept in step: exact_damping reads it
            extra = np.zeros(cpu.nv)
            extra[k_api.ROOT_DOFS :] = motor_damping(self._hinge_gears, phys.motor_speed)
            cpu.dof_damping[:] += extra
            damping += extra
            if phys.exact_damping:  # of the damping in all, at the substep
                dofs, scale = exact_damping_scale(mujoco, cpu, self.dt / self.substeps)
                damping[..., dofs] *= scale
            solver.mjw_model.dof_damping.assign(damping)
        opt = solver.mjw_model.opt  # some kernels are specialised to these options
        opt.warn_overflow = int(opt.warn_overflow) & self._quiet_bits
        return solver

    def _rehearse(self, preload, build_model) -> tuple[int, object]:
        """Queue the kernels MuJoCo Warp specialises to the model while it builds and first steps it.

        A rehearsal on two worlds names them (a few depend on the world count: the step's own rehearsal
        catches those), so they compile beside the modules already queued, and while the full model is
        built, instead of one by one at their first launch. Returns how many were queued and what stopped
        the preload early, if anything."""
        queued = preload.add(lambda: build_model(REHEARSAL_WORLDS))  # the finalize kernels
        stopped_early = preload.stopped_early
        small = build_model(REHEARSAL_WORLDS)

        def rehearse():  # a launch-free construction and substep, contact forces on as tasks want them
            solver = self._make_solver(small)
            solver.mjw_model.opt.run_rne_postconstraint = True
            state, control = small.state(), small.control()
            solver.step(state, state, control, None, self.dt / self.substeps)

        queued += preload.add(rehearse)
        return queued, stopped_early or preload.stopped_early

    def _read_layout(self, model, path: str) -> None:
        """Per-env counts, body and joint names, feet, joint limits and gears, checked against the robot a
        task expects: a free root joint and one hinge per actuated dof."""
        n = self.num_envs
        self.coords_per_env = model.joint_coord_count // n
        self.dofs_per_env = model.joint_dof_count // n
        self.bodies_per_env = model.body_count // n
        self.num_dofs = self.dofs_per_env - k_api.ROOT_DOFS
        self.body_names = [_leaf(s) for s in model.body_label[: self.bodies_per_env]]
        self._joints_per_env = model.joint_count // n
        self._dof_dims = model.joint_dof_dim.numpy()[: self._joints_per_env].sum(axis=1)
        self.dof_names = hinge_joint_names(path)
        missing = [f for f in self.spec.feet if f not in self.body_names]
        if missing:
            raise ValueError(f"{self.spec.mjcf} has no bodies named {missing}; its bodies are {self.body_names}")
        self.foot_bodies = wp.array([self.body_names.index(f) for f in self.spec.feet], dtype=wp.int32,
                                    device=self.device)
        if (
            int(self._dof_dims[0]) != k_api.ROOT_DOFS
            or self.coords_per_env - k_api.ROOT_COORDS != self.num_dofs
            or len(self.dof_names) != self.num_dofs
        ):
            raise ValueError(f"{self.spec.mjcf}: expected a free root joint and {self.num_dofs} hinge joints below it")

        lower = model.joint_limit_lower.numpy()[k_api.ROOT_DOFS : self.dofs_per_env]
        upper = model.joint_limit_upper.numpy()[k_api.ROOT_DOFS : self.dofs_per_env]
        self.dof_lower_np = lower.astype(np.float32)
        self.dof_upper_np = upper.astype(np.float32)
        self.default_dof_pos_np = np.clip(0.0, lower, upper).astype(np.float32)
        self.motor_gear_np = np.array([self._gears_by_joint.get(name, 0.0) for name in self.dof_names], np.float32)

    def _set_start_state(self, model) -> None:
        """Root upright at the robot's start height, dofs at 0 clamped into their limits; the armature set."""
        n = self.num_envs
        q = model.joint_q.numpy().reshape(n, self.coords_per_env)
        q[:, :7] = (0.0, 0.0, self.spec.start_height, 0.0, 0.0, 0.0, 1.0)
        q[:, 7:] = self.default_dof_pos_np
        model.joint_q.assign(q.reshape(-1))
        model.joint_qd.zero_()
        if self.physics.armature is not None:
            armature = model.joint_armature.numpy().reshape(n, self.dofs_per_env)
            armature[:, k_api.ROOT_DOFS :] = self.physics.armature
            model.joint_armature.assign(armature.reshape(-1))

    def _make_state(self, model) -> None:
        """The state and control the steps write, their 2-D views, the solver-load counters and the map from
        Newton's dofs to MuJoCo's."""
        n = self.num_envs
        self._peak_nefc = wp.zeros(n, dtype=wp.int32, device=self.device)
        self._peak_nacon = wp.zeros(1, dtype=wp.int32, device=self.device)
        self._overflowed = wp.zeros(n, dtype=wp.int32, device=self.device)
        self.state = model.state()
        self.control = model.control()
        self.control.joint_f.zero_()

        # 2-D views of Newton's flat arrays; they share memory and never move.
        self.joint_q = self.state.joint_q.reshape((n, self.coords_per_env))
        self.joint_qd = self.state.joint_qd.reshape((n, self.dofs_per_env))
        self.joint_f = self.control.joint_f.reshape((n, self.dofs_per_env))

        # Newton merges the hinges of one body into a single joint; MuJoCo keeps one dof per hinge,
        # in the same order, so each Newton joint's dofs map onto a contiguous MuJoCo range.
        mj_qd_start = self.solver.mj_qd_start.numpy()
        dims = self._dof_dims
        to_mj = np.concatenate([mj_qd_start[j] + np.arange(dims[j]) for j in range(1, self._joints_per_env)])
        self.newton_to_mj_dof = wp.array(to_mj.astype(np.int32), dtype=wp.int32, device=self.device)

    # ------------------------------------------------------------------ stepping
    @property
    def sub_dt(self) -> float:
        return self.dt / self.substeps

    def simulate(self) -> None:
        """Advance one control step as plain launches (what the captured graph holds)."""
        d, opt = self.solver.mjw_data, self.solver.mjw_model.opt
        once = self.convert_once_per_step and self.physics.max_joint_speed is None
        last = self.substeps - 1
        for i in range(self.substeps):
            # Contact wrenches are read after the last substep only. MuJoCo Warp checks this flag on
            # the host at each step, so the captured graph holds the extra pass once per control step.
            opt.run_rne_postconstraint = self._contact_forces and i == last
            if once:
                self._mujoco_substep(push=i == 0, pull=i == last)
            else:
                self.solver.step(self.state, self.state, self.control, None, self.sub_dt)
                if self.physics.max_joint_speed is not None:  # a clamp on Newton's state: every substep
                    wp.launch(k_api.clamp_dof_speed, dim=(self.num_envs, self.num_dofs),
                              inputs=[self.physics.max_joint_speed], outputs=[self.joint_qd], device=self.device)
            wp.launch(track_solver_load, dim=self.num_envs,
                      inputs=[d.nefc, d.nacon, self._drop_bits, int(i == 0)],
                      outputs=[d.overflow, self._peak_nefc, self._peak_nacon, self._overflowed], device=self.device)

    def _mujoco_substep(self, push: bool, pull: bool) -> None:
        # Newton's state goes in before the first substep and out after the last (newton_internals)
        newton_internals.mujoco_substep(self.solver, self.model, self.state, self.control, self.sub_dt,
                                        self.device, push=push, pull=pull)

    @property
    def solver_overflows(self) -> wp.array:
        """(N,) int32: substeps of the last step in which each world lost constraints or contacts
        because MuJoCo Warp's buffers (``njmax``, ``naconmax``) were full."""
        return self._overflowed

    def solver_load(self) -> dict:
        """How full the constraint and contact buffers have been since the Sim was built (or
        ``reset_solver_load()``): the most constraint rows of any world against ``njmax``, and the
        most contacts of all worlds in one substep against ``naconmax``. One host read."""
        d = self.solver.mjw_data
        peak_nacon = int(self._peak_nacon.numpy()[0])
        return {"njmax": int(d.njmax), "peak_constraints_per_world": int(self._peak_nefc.numpy().max()),
                "naconmax": int(d.naconmax), "peak_contacts": peak_nacon,
                "peak_contacts_per_world_mean": peak_nacon / self.num_envs}

    def reset_solver_load(self) -> None:
        self._peak_nefc.zero_()
        self._peak_nacon.zero_()

    def compile_ahead(self, fn) -> None:
        """Compile, side by side, every module ``fn``'s launches need (``warpgym.compile.preload``). Newton
        counts solver steps on the host; the launch-free pass must not move that count."""
        with newton_internals.keep_step_count(self.solver):
            self.compile_log.append(("step", compile_ahead(fn)))

    def enable_contact_forces(self) -> None:
        """Have the solver compute per-body contact wrenches (MuJoCo's ``cfrc_ext``) in the last
        substep of every step."""
        if not self._contact_forces:
            self._contact_forces = True
            self._graph = None  # the captured graph lacks the extra pass

    def clear_warm_start(self, env_ids: wp.array) -> None:
        """Forget the solver's warm start for worlds whose state was written from outside."""
        if env_ids.shape[0] == 0:
            return
        warm = self.solver.mjw_data.qacc_warmstart
        wp.launch(k_api.clear_warmstart_indexed, dim=(env_ids.shape[0], warm.shape[1]),
                  inputs=[env_ids, warm], device=self.device)

    # ------------------------------------------------------------------ helpers
    def to_torch(self, array: wp.array) -> torch.Tensor:
        return wp.to_torch(array, requires_grad=False)

    def warp_buffer(self, key: str, shape, dtype=wp.float32) -> tuple[wp.array, torch.Tensor]:
        """A persistent (Warp array, torch view) pair, allocated on first request."""
        if key not in self._tensors:
            arr = wp.zeros(shape, dtype=dtype, device=self.device)
            self._tensors[key] = (arr, self.to_torch(arr))
        return self._tensors[key]

    def __repr__(self) -> str:
        return (f"Sim(robot={self.spec.name!r}, num_envs={self.num_envs}, device={self.device!r}, "
                f"dt={self.dt:.5g}, substeps={self.substeps}, physics={self.physics}, dofs={self.num_dofs}, bodies={self.bodies_per_env})")
