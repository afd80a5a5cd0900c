"""The private parts of Newton's ``SolverMuJoCo`` that warpgym calls, in one place.

Newton's public ``SolverMuJoCo.step`` converts Newton's state into MuJoCo Warp's data before every
substep and back after it. With several substeps per control step nothing reads Newton's state in
between, so ``Sim`` pushes the state in before the first substep and pulls it out after the last:
about a tenth of the Ant's physics time on an H100 (``warpgym bench``, "MuJoCo Warp" against "raw
Newton"). That needs the solver's phases one by one, which are private in newton 1.8 (pinned in
pyproject.toml). ``tests/test_sim.py`` checks this path against the public step, so a Newton upgrade
that moves them breaks here and in that test, nowhere else."""

from __future__ import annotations

import contextlib

import warp as wp

PHASES = ("_scoped_mujoco_warp_execution", "_apply_mjc_control", "_update_mjc_data", "_mujoco_warp_step",
          "_update_newton_state")


def supports_split_substeps(solver) -> bool:
    """Whether this SolverMuJoCo has the private phases ``mujoco_substep`` calls."""
    return all(callable(getattr(solver, name, None)) for name in PHASES)


@contextlib.contextmanager
def compile_options(solver, device):
    """The scope under which the solver launches MuJoCo Warp's kernels (its compile options), for code
    that launches MuJoCo Warp directly and must hit the same compiled kernels."""
    with wp.ScopedDevice(device), solver._scoped_mujoco_warp_execution():
        yield


def mujoco_substep(solver, model, state, control, sub_dt: float, device, push: bool, pull: bool) -> None:
    """One substep on MuJoCo Warp's data: ``SolverMuJoCo.step``'s phases, with Newton's ``state`` pushed
    in only when ``push`` (before the first substep) and pulled out, forward kinematics of every body
    included, only when ``pull`` (after the last)."""
    with compile_options(solver, device):
        if push:
            solver._apply_mjc_control(model, state, control, solver.mjw_data)
            solver._update_mjc_data(solver.mjw_data, model, state)
            solver.mjw_model.opt.timestep.fill_(sub_dt)
        solver._mujoco_warp_step()
        if pull:
            solver._update_newton_state(model, state, solver.mjw_data, state_prev=state)
    solver._step += 1


@contextlib.contextmanager
def keep_step_count(solver):
    """Newton counts solver steps on the host (``SolverMuJoCo._step``); a launch-free compile pass over a
    step must leave the count where it was."""
    count = getattr(solver, "_step", None)
    try:
        yield
    finally:
        if count is not None:
            solver._step = count
