"""libmathdx LTO objects noted, built ahead (here or in a child process), then found by the compile.

Warp compiles CUDA code with its bundled NVRTC and libmathdx even without a GPU, so these run on
the CPU: they compile for sm_90 into a kernel cache of their own."""

import random

import pytest
import warp as wp
import warp._src.context as wp_context

from warpgym.compile import mathdx

wp.init()
runtime = wp_context.runtime
pytestmark = pytest.mark.skipif(not runtime.core.wp_is_mathdx_enabled(), reason="this Warp build has no libmathdx")
ARCH = 90
TILE = 6


def _cholesky_module(block_dim: int):
    scale = random.SystemRandom().random() + 1.0  # a constant no cache has seen (from the OS, whatever seeds random)

    @wp.kernel(module="unique", enable_backward=False)
    def factor(a: wp.array2d(dtype=float), out: wp.array2d(dtype=float)):
        t = wp.tile_load(a, shape=(TILE, TILE), storage="shared")
        wp.tile_cholesky_inplace(t)
        wp.tile_store(out, t * scale)

    return factor.module, block_dim


@pytest.fixture
def own_cache(tmp_path, monkeypatch):
    monkeypatch.setattr(wp.config, "kernel_cache_dir", str(tmp_path))
    return tmp_path


@pytest.fixture
def solver_builds(monkeypatch):
    """Counts libmathdx's Cholesky builds in this process."""
    count = {"n": 0}
    original = runtime.core.wp_cuda_compile_solver

    def counting(*args):
        count["n"] += 1
        return original(*args)

    monkeypatch.setattr(runtime.core, "wp_cuda_compile_solver", counting)
    return count


def _compile(module, block_dim):
    module._compile(device=None, output_arch=ARCH, options=module.resolve_options(wp.config, block_dim=block_dim))


def test_a_module_without_tile_solvers_notes_nothing(own_cache):
    @wp.kernel(module="unique")
    def plain(x: wp.array(dtype=float)):
        x[wp.tid()] = 1.0

    assert mathdx.lto_requests(plain.module, ARCH, 64) == []


def test_noted_objects_built_here_leave_the_compile_nothing_to_build(own_cache, solver_builds):
    module, block_dim = _cholesky_module(64)
    requests = mathdx.lto_requests(module, ARCH, block_dim)
    assert [r.builder for r in requests] == ["build_lto_solver"]
    assert requests[0].symbol.startswith(f"potrf_{TILE}_{TILE}_") and f"_{block_dim}_" in requests[0].symbol
    assert solver_builds["n"] == 0  # noting builds nothing
    mathdx.build(requests[0])
    assert solver_builds["n"] == 1
    assert mathdx.lto_requests(module, ARCH, block_dim) == []  # the cache has it now
    _compile(module, block_dim)
    assert solver_builds["n"] == 1  # the compile read it from the cache
    assert list(own_cache.glob("wp_*/*.sm90.cubin"))


def test_another_block_size_needs_its_own_object(own_cache):
    module, _ = _cholesky_module(64)
    (r64,) = mathdx.lto_requests(module, ARCH, 64)
    mathdx.build(r64)
    (r32,) = mathdx.lto_requests(module, ARCH, 32)
    assert r32.symbol != r64.symbol


def test_a_child_process_builds_the_object_into_this_cache(own_cache, solver_builds):
    module, block_dim = _cholesky_module(32)
    requests = mathdx.lto_requests(module, ARCH, block_dim)
    (child,) = mathdx.start_builds(requests)
    assert mathdx.start_builds(requests) == [child]  # one child per object, however often asked
    assert child.wait() is True
    assert mathdx.lto_requests(module, ARCH, block_dim) == []
    _compile(module, block_dim)
    assert solver_builds["n"] == 0  # nothing was built in this process


def test_a_failed_child_reports_and_leaves_the_object_to_the_compile(own_cache, solver_builds):
    module, block_dim = _cholesky_module(64)
    (request,) = mathdx.lto_requests(module, ARCH, block_dim)
    broken = mathdx.Request(request.symbol + "_broken", request.builder, {**request.arguments, "M": -1})
    child = mathdx.ChildBuild(broken)
    assert child.wait() is False
    _compile(module, block_dim)  # the compile builds what the child could not
    assert solver_builds["n"] == 1
