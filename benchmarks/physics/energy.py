"""The energy account of a native-MuJoCo replay, for the studies of the physics step (fidelity.py and
step_sensitivity.py): where the mechanical energy of a robot comes from and goes, force by force, and what the
integrator adds beyond all of them (the step's own error)."""

from __future__ import annotations

import numpy as np


class PowerMeter:
    """An energy account of a replay, as ``NativeRobot.on_substep``: the work of the motors, joint
    damping, contacts and joint limits (each force times the substep's mean velocity), what the
    mechanical energy gained beyond them (the integrator's: the step's own error, 0 in the continuous
    model), and the robot-seconds stepped. ``watts()``: each as mean power per robot."""

    def __init__(self, model):
        import mujoco  # noqa: PLC0415

        self.mj, self.m = mujoco, model
        self.work = {"motors": 0.0, "damping": 0.0, "contacts": 0.0, "limits": 0.0, "integrator": 0.0}
        self.seconds = 0.0
        c = mujoco.mjtConstraint
        self.contact_types = (c.mjCNSTR_CONTACT_FRICTIONLESS, c.mjCNSTR_CONTACT_PYRAMIDAL, c.mjCNSTR_CONTACT_ELLIPTIC)
        self.jac = np.zeros((0, model.nv))
        self.scratch, self.energy = mujoco.MjData(model), {}

    def mechanical_energy(self, d) -> float:
        """Potential plus kinetic energy of ``d``'s state, computed on a scratch copy so that the
        replay's own data (and what its observations read) is left as the step left it."""
        s, mj = self.scratch, self.mj
        s.qpos[:], s.qvel[:] = d.qpos, d.qvel
        mj.mj_kinematics(self.m, s)
        mj.mj_comPos(self.m, s)
        mj.mj_makeM(self.m, s)
        mj.mj_energyPos(self.m, s)
        mj.mj_energyVel(self.m, s)
        return float(s.energy[0] + s.energy[1])

    def __call__(self, copy: int, d, before: np.ndarray) -> None:
        m, dt, w = self.m, self.m.opt.timestep, self.work
        v = 0.5 * (before + d.qvel)
        self.seconds += dt
        motors, damping = dt * d.qfrc_applied @ v, dt * d.qfrc_passive @ v
        w["motors"] += motors
        w["damping"] += damping
        paid = motors + damping
        if d.nefc:
            if self.jac.shape[0] != d.nefc:
                self.jac = np.zeros((d.nefc, m.nv))
            if self.mj.mj_isSparse(m):
                self.mj.mju_sparse2dense(self.jac, d.efc_J, d.efc_J_rownnz, d.efc_J_rowadr, d.efc_J_colind)
            else:
                self.jac[:] = d.efc_J.reshape(d.nefc, m.nv)
            power = d.efc_force[:d.nefc] * (self.jac @ v)
            kind = d.efc_type[:d.nefc]
            w["contacts"] += dt * power[np.isin(kind, self.contact_types)].sum()
            w["limits"] += dt * power[kind == self.mj.mjtConstraint.mjCNSTR_LIMIT_JOINT].sum()
            paid += dt * power.sum()
        # what the state gained beyond the forces' work: the step's own error (0 in the continuous model);
        # a copy's first substep only sets its reference
        energy = self.mechanical_energy(d)
        if copy in self.energy:
            w["integrator"] += energy - self.energy[copy] - paid
        self.energy[copy] = energy

    def watts(self) -> dict:
        return {k: round(v / self.seconds, 1) for k, v in self.work.items()}
