"""The kernel preload: which modules, without adjoints, and a failure that does not stop the build."""

import importlib

import warp as wp

from warpgym import preload


def test_sim_modules_are_set_to_skip_adjoint_code():
    preload.Preload("cpu").wait()
    for name in ("kernels.actions", "kernels.locomotion", "kernels.resets", "kernels.tensor_api",
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
