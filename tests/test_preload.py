"""The kernel preload: which modules, without adjoints, and a failure that does not stop the build."""

import importlib

import warp as wp

from warpgym.compile import log as compile_log, preload


def test_sim_modules_are_set_to_skip_adjoint_code():
    preload.Preload("cpu").wait()
    for name in ("kernels.common", "kernels.robots.actions", "kernels.robots.step", "kernels.robots.resets",
                 "kernels.tensor_api",
                 *preload.NO_BACKWARD):
        assert wp.get_module_options(importlib.import_module(name))["enable_backward"] is False, name


def test_every_listed_module_exists_in_the_pinned_dependencies():
    # a name that moved in a Newton or MuJoCo Warp release is skipped silently at run time; here it fails
    p = preload.Preload("cpu")
    p.wait()
    assert p.error is None
    assert [m.__name__ for m in p.modules] == list(preload.SIM_MODULES)


def test_a_failed_preload_is_kept_for_the_first_launch_to_report(monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("compiler crashed")

    monkeypatch.setattr(preload.wp, "load_module", broken)
    p = preload.Preload("cpu")
    p.wait()  # does not raise: the same module fails again, with its context, where it is launched
    assert isinstance(p.error, RuntimeError)


def _constant_kernel(value: float):
    @wp.kernel(module="unique", enable_backward=False)
    def fill(out: wp.array(dtype=float)):
        out[wp.tid()] = value

    return fill


def test_a_recorded_launch_names_its_module_and_runs_nothing():
    kernel = _constant_kernel(7.0)
    out = wp.zeros(4, dtype=float, device="cpu")
    compiled_before = len(compile_log.compiled_modules())
    found, error = preload.record_modules(lambda: wp.launch(kernel, dim=4, outputs=[out], device="cpu"))
    assert error is None
    assert [m for m, _, _ in found] == [kernel.module]
    assert out.numpy().tolist() == [0.0] * 4  # skipped, not run
    assert len(compile_log.compiled_modules()) == compiled_before  # and not compiled either
    wp.launch(kernel, dim=4, outputs=[out], device="cpu")  # outside the recording, launches run again
    assert out.numpy().tolist() == [7.0] * 4


def test_device_loops_and_branches_are_walked_once_each_while_recording():
    flag = wp.zeros(1, dtype=int, device="cpu")  # 0: a real loop or branch would never enter
    seen = []
    found, _ = preload.record_modules(lambda: (
        wp.capture_while(flag, lambda: seen.append("loop body")),
        wp.capture_if(flag, on_true=lambda: seen.append("if"), on_false=lambda: seen.append("else")),
    ))
    assert seen == ["loop body", "if", "else"]
    wp.capture_while(flag, lambda: seen.append("after"))  # Warp's own again: the condition is read
    assert seen == ["loop body", "if", "else"]


def test_compile_ahead_compiles_what_the_launch_then_finds_ready():
    import random

    # a new constant: a hash no cache has seen (from the OS: hypothesis's tests seed the random module)
    kernel = _constant_kernel(random.SystemRandom().random())
    out = wp.zeros(2, dtype=float, device="cpu")

    def launch():
        wp.launch(kernel, dim=2, outputs=[out], device="cpu")

    report = preload.compile_ahead(launch)
    assert (report["modules"], report["loaded"], report["compiled"]) == (1, 1, 1)
    assert compile_log.compiled_modules()[-1][0] == kernel.module.name
    count = len(compile_log.compiled_modules())
    launch()
    assert len(compile_log.compiled_modules()) == count
    assert out.numpy()[0] > 0


def test_a_built_sim_has_every_module_of_its_step_loaded():
    # njmax is baked into some of MuJoCo Warp's kernels; an odd value makes sure this Sim's own
    # rehearsal, not an earlier test, loaded them
    from warpgym import Sim

    sim = Sim("ant", num_envs=3, device="cpu", njmax=131)  # not the rehearsal's world count
    sim.enable_contact_forces()
    found, error = preload.record_modules(sim.simulate)
    assert error is None
    names = [m.name for m, _, _ in found]
    assert any(n.startswith("_update_gradient_JTDAJ") for n in names), names
    missing = [m.name for m, d, b in found if not preload._is_loaded(m, d, b)]
    assert missing == [], (missing, sim.compile_log)


def test_a_start_without_cached_bytecode_says_how_to_cache_it(monkeypatch, tmp_path):
    import importlib.util
    import sys
    from types import SimpleNamespace

    assert preload.bytecode_note() == "" or sys.flags.dont_write_bytecode  # this machine caches bytecode
    monkeypatch.setattr(sys, "flags", SimpleNamespace(dont_write_bytecode=1))
    monkeypatch.setattr(importlib.util, "cache_from_source", lambda path: str(tmp_path / "missing.pyc"))
    note = preload.bytecode_note()
    assert "PYTHONDONTWRITEBYTECODE" in note and "python -m compileall -q " in note
    site = note.split("python -m compileall -q ")[1].split("`")[0]
    assert importlib.util.find_spec("torch").origin.startswith(site)
