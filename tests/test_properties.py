"""Property-based input tests: every Tensor API setter and ``env.step`` take generated inputs of
every wrong kind (dtype, device, shape, non-contiguous, out-of-range and duplicate indices, NaN and
inf values). Each case either raises a clear error that names the argument, or is taken; a taken
NaN/inf ends as a flagged reset of its own world, and no other world's observation turns non-finite.

Cases tried per run: ``EXAMPLES`` per property, 4 properties (see the settings below)."""

import numpy as np
import pytest
import torch
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

EXAMPLES = 150
SETTINGS = settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
N, K = 4, 8  # the ant_env fixture: 4 Ants of 8 joints
DTYPES = [torch.float32, torch.float64, torch.float16, torch.int32, torch.int64, torch.bool]


def rarely(draw, p: float) -> bool:
    return draw(st.integers(0, 99)) < 100 * p


@st.composite
def tensors(draw, shapes):
    """A tensor the API wants (one of ``shapes``, float32, on the CPU) about half the time; otherwise
    with a wrong shape, dtype or device, or several. Either way it may be non-contiguous and may hold
    NaN, inf or huge entries."""
    shape = draw(st.sampled_from(shapes))
    if rarely(draw, 0.25):
        shape = draw(st.lists(st.integers(0, 9), min_size=0, max_size=3).map(tuple))
    dtype = draw(st.sampled_from(DTYPES)) if rarely(draw, 0.25) else torch.float32
    transposed = len(shape) == 2 and draw(st.booleans())
    t = torch.zeros(shape[::-1], dtype=torch.float64).t() if transposed else torch.zeros(shape, dtype=torch.float64)
    if t.numel():
        t += draw(st.floats(-3, 3))
        for _ in range(draw(st.integers(0, 3))):  # poison some entries
            where = np.unravel_index(draw(st.integers(0, t.numel() - 1)), tuple(t.shape))
            t[where] = draw(st.sampled_from([float("nan"), float("inf"), -float("inf"), 1e30]))
    t = t.to(dtype)
    return t.to("meta") if rarely(draw, 0.1) else t  # a tensor on another device


def expected_error(name, t, shapes):
    """The documented checks, in order: tensor, device, dtype, shape (warpgym/sim/checks.py)."""
    if t.device.type != "cpu":
        return ValueError, f"{name} is on {t.device}"
    if t.dtype != torch.float32:
        return TypeError, f"{name} has dtype {t.dtype}"
    if tuple(t.shape) not in shapes:
        return ValueError, f"{name} has shape {tuple(t.shape)}"
    return None


@st.composite
def env_ids(draw):
    """Indices of existing envs, duplicates allowed, most of the time; else out of range, of a
    non-integer dtype, or 2-D."""
    high = N + 1 if rarely(draw, 0.2) else N - 1
    low = -2 if rarely(draw, 0.1) else 0
    t = torch.tensor(draw(st.lists(st.integers(low, high), min_size=0, max_size=6)), dtype=torch.int64)
    if rarely(draw, 0.15):
        t = t.to(draw(st.sampled_from([torch.float32, torch.int16, torch.bool])))
    elif draw(st.booleans()):
        t = t.to(torch.int32)
    return t.view(-1, 1) if rarely(draw, 0.1) else t


def expected_ids_error(ids):
    if ids.dtype not in (torch.int32, torch.int64):
        return TypeError, f"env_ids has dtype {ids.dtype}"
    if ids.dim() != 1:
        return ValueError, "env_ids has shape"
    if ids.numel() and (int(ids.min()) < 0 or int(ids.max()) >= N):
        return IndexError, "outside [0, 3]"
    return None


def step_and_check(env, poisoned_worlds=()):
    """A step after the input: every observation finite; a world given NaN/inf state is reset and flagged."""
    before = int(env.fault_counters()["diverged_resets"])
    obs, rew, term, trunc, info = env.step(torch.zeros(N, K))
    assert torch.isfinite(obs).all() and torch.isfinite(rew).all()
    assert torch.isfinite(env.sim.root_pose).all() and torch.isfinite(env.sim.dof_vel).all()
    for i in poisoned_worlds:
        assert bool(info["diverged"][i]), i
    event(f"worlds poisoned: {len(poisoned_worlds)}")
    assert int(env.fault_counters()["diverged_resets"]) - before >= len(poisoned_worlds)


def run_case(call, expected):
    if expected is None:
        call()
        event("taken")
        return True
    error, text = expected
    event(f"refused: {error.__name__}")
    with pytest.raises(error) as caught:
        call()
    assert text in str(caught.value), (str(caught.value), text)
    return False


@SETTINGS
@given(actions=tensors([(N, K)]))
def test_env_step_takes_or_refuses_any_action_tensor(ant_env, actions):
    ant_env.reset(seed=0)
    expected = expected_error("actions", actions, [(N, K)])
    counted = int(ant_env.fault_counters()["nan_actions"])
    if run_case(lambda: ant_env.step(actions), expected):
        bad = int((~torch.isfinite(actions)).sum())
        assert int(ant_env.fault_counters()["nan_actions"]) - counted == bad  # applied as 0, counted
        assert torch.isfinite(ant_env.obs).all()
    step_and_check(ant_env)


@SETTINGS
@given(forces=tensors([(N * K,), (N, K)]))
def test_joint_force_setter_takes_or_refuses_any_tensor(ant_env, forces):
    ant_env.reset(seed=0)
    expected = expected_error("forces", forces, [(N * K,), (N, K)])
    run_case(lambda: ant_env.sim.set_dof_actuation_force_tensor(forces), expected)
    # the env overwrites joint torques from its actions every step: the step shows no trace of it
    step_and_check(ant_env)


@SETTINGS
@given(states=tensors([(N, 13)]), ids=env_ids())
def test_root_state_setter_takes_or_refuses_any_input(ant_env, states, ids):
    ant_env.reset(seed=0)
    expected = expected_error("states", states, [(N, 13)]) or expected_ids_error(ids)
    if run_case(lambda: ant_env.sim.set_actor_root_state_tensor_indexed(states, ids), expected):
        written = set(ids.tolist())  # duplicates write the same row twice: allowed
        poisoned = [i for i in written if not torch.isfinite(states[i]).all() or states[i].abs().max() > 1e6]
        step_and_check(ant_env, poisoned)
    else:
        step_and_check(ant_env)


@SETTINGS
@given(states=tensors([(N * K, 2)]), ids=env_ids())
def test_dof_state_setter_takes_or_refuses_any_input(ant_env, states, ids):
    ant_env.reset(seed=0)
    expected = expected_error("states", states, [(N * K, 2)]) or expected_ids_error(ids)
    if run_case(lambda: ant_env.sim.set_dof_state_tensor_indexed(states, ids), expected):
        rows = states.view(N, K, 2)
        poisoned = [i for i in set(ids.tolist()) if not torch.isfinite(rows[i]).all()]
        step_and_check(ant_env, poisoned)
    else:
        step_and_check(ant_env)
