"""warpgym's suite against Gymnasium's own envs: one step from the same states, and the distributions
of random-action episodes. Used by `warpgym eval`, tests/test_suite.py and
benchmarks/physics/conformance.py.

"The same state" is everything Gymnasium's ``step`` reads before it simulates: qpos, qvel, the
solver's warm start, and the position the forward speed is measured from (a body position as the
last physics step left it, for Ant and Humanoid). States come from Gymnasium's env itself: its reset
states and states along random-action episodes.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import torch

from kernels.suite import params as G
from warpgym.tasks.suite import SUITE, GymTask, get_suite_task

if TYPE_CHECKING:  # the env is a layer above; these functions take one built by the caller
    from warpgym.envs.suite import SuiteVecEnv


def gymnasium_env(task: str | GymTask, version: int = 5, **kwargs):
    """``gymnasium.make`` of the same task with the same constructor arguments (TimeLimit included).
    ``version=4``: Gymnasium's v4 of it instead, with v4's own defaults (v5's arguments it does not take)."""
    import gymnasium  # noqa: PLC0415

    task = get_suite_task(task)
    if version == 5:
        args = {name: getattr(task, name) for name in task.argument_names()}
        return gymnasium.make(task.gymnasium_id, max_episode_steps=task.episode_length, **args, **kwargs)
    if version != 4 or task.v4_observation is None:
        raise ValueError(f"{task.name} in Gymnasium's v{version}: warpgym plays v5 policies in v5, and in v4 "
                         f"for {v4_tasks()} (whose v4 observation holds v5's)")
    with warnings.catch_warnings():  # v4 is out of date on purpose: it is what older figures were made in
        warnings.simplefilter("ignore", DeprecationWarning)
        return gymnasium.make(task.version_name(4), max_episode_steps=task.episode_length, **kwargs)


def v4_tasks() -> list[str]:
    return [name for name, task in SUITE.items() if task.v4_observation is not None]


def reference_position(task: GymTask, env) -> np.ndarray:
    """The (x, y) Gymnasium's next ``step`` measures the forward speed from, read off its data."""
    u = env.unwrapped
    model, data = u.model, u.data
    if task.kind != G.FORWARD:
        return np.zeros(2)
    p = task.params(_Shape(model, u.frame_skip))
    if p.position_source == G.POSITION_QPOS_X:
        return np.array([data.qpos[0], 0.0])
    if p.position_source == G.POSITION_QPOS_XY:
        return data.qpos[:2].copy()
    if p.position_source == G.POSITION_BODY:
        return data.xpos[p.main_body, :2].copy()
    return (model.body_mass @ data.xipos / model.body_mass.sum())[:2]


class _Shape:
    """What ``GymTask.params`` reads of a sim, from a MuJoCo model (for ``reference_position``)."""

    def __init__(self, model, frame_skip: int):
        import mujoco  # noqa: PLC0415

        self.mjm, self.nq, self.nv, self.nu, self.nbody = model, model.nq, model.nv, model.nu, model.nbody
        self.timestep = float(model.opt.timestep)
        self.dt = self.timestep * frame_skip
        self.body_names = [mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, b) or "" for b in range(model.nbody)]


@dataclass
class Sample:
    """One Gymnasium step: the state before it, the action, and what Gymnasium returned."""

    qpos: np.ndarray
    qvel: np.ndarray
    warm_start: np.ndarray
    before: np.ndarray
    action: np.ndarray
    obs: np.ndarray
    reward: float
    terms: dict
    terminated: bool
    after_reset: bool


def gymnasium_samples(task: GymTask, episodes: int, steps_apart: int, per_episode: int, seed: int = 0) -> list[Sample]:
    """Steps of Gymnasium's env from its reset states and along random-action episodes: every
    ``steps_apart``-th step of each episode, ``per_episode`` of them (fewer if it ends)."""
    env = gymnasium_env(task)
    rng = np.random.default_rng(seed)
    out = []
    for e in range(episodes):
        env.reset(seed=seed * 1000 + e)
        u = env.unwrapped
        for t in range(steps_apart * per_episode):
            action = rng.uniform(env.action_space.low, env.action_space.high).astype(np.float32)
            keep = t % steps_apart == 0
            if keep:
                state = (u.data.qpos.copy(), u.data.qvel.copy(), u.data.qacc_warmstart.copy(),
                         reference_position(task, env))
            obs, reward, terminated, truncated, info = env.step(action)
            if keep:
                terms = {k: float(info[k]) for k in task.info_keys if k in info}
                out.append(Sample(*state, action, obs, float(reward), terms, bool(terminated), t == 0))
            if terminated or truncated:
                break
    env.close()
    return out


@dataclass
class StepGaps:
    """The largest differences between warpgym's step and Gymnasium's over the samples."""

    samples: int
    obs: float = 0.0  # max |warpgym - Gymnasium| / (1 + |Gymnasium|) over observation entries
    reward: float = 0.0  # same, for the reward
    terms: dict = field(default_factory=dict)
    terminated_mismatches: int = 0
    worst_obs_entry: int = -1
    obs_by_entry: np.ndarray | None = None  # the largest difference of each observation entry


def put_states(env: SuiteVecEnv, states: list[tuple]) -> None:
    """Put Gymnasium's states into the first worlds of ``env``, as its next ``step`` reads them: each
    ``(qpos, qvel, before, warm_start)`` (``before``: ``reference_position``; ``warm_start`` None: none),
    their episodes starting there."""
    sim = env.sim
    qpos, qvel = sim.dof_pos.clone(), sim.dof_vel.clone()
    for i, (qp, qv, _, _) in enumerate(states):
        qpos[i] = torch.as_tensor(qp, dtype=torch.float32)
        qvel[i] = torch.as_tensor(qv, dtype=torch.float32)
    sim.set_state(qpos, qvel)  # clears the warm starts
    warm, before = sim.to_torch(sim.d.qacc_warmstart), sim.to_torch(env._episodes.before)
    for i, (_, _, ref, warm_start) in enumerate(states):
        before[i] = torch.as_tensor(ref, dtype=torch.float32)
        if warm_start is not None:
            warm[i] = torch.as_tensor(warm_start, dtype=torch.float32)
    env.episode_steps.zero_()


def compare_steps(env: SuiteVecEnv, samples: list[Sample]) -> StepGaps:
    """Put each sample's state into one world of ``env``, step every world once with the samples'
    actions, and measure the differences. ``env.num_envs`` must be at least ``len(samples)``."""
    n = len(samples)
    if env.num_envs < n:
        raise ValueError(f"{n} samples need num_envs >= {n}, got {env.num_envs}")
    dev = env.device
    actions = torch.zeros(env.num_envs, env.num_actions, device=dev)
    for i, s in enumerate(samples):
        actions[i] = torch.as_tensor(s.action)
    put_states(env, [(s.qpos, s.qvel, s.before, s.warm_start) for s in samples])
    obs, reward, terminated, truncated, info = env.step(actions)
    done = (terminated | truncated).cpu().numpy()
    obs = torch.where(torch.as_tensor(done, device=dev)[:, None], info["final_obs"], obs).cpu().numpy().astype(np.float64)
    reward, terminated = reward.cpu().numpy().astype(np.float64), terminated.cpu().numpy()
    gaps = StepGaps(n, obs_by_entry=np.zeros(obs.shape[1]))
    for i, s in enumerate(samples):
        rel = np.abs(obs[i] - s.obs) / (1.0 + np.abs(s.obs))
        np.maximum(gaps.obs_by_entry, rel, out=gaps.obs_by_entry)
        if rel.size and rel.max() > gaps.obs:
            gaps.obs, gaps.worst_obs_entry = float(rel.max()), int(rel.argmax())
        gaps.reward = max(gaps.reward, abs(reward[i] - s.reward) / (1.0 + abs(s.reward)))
        for key, value in s.terms.items():
            mine = float(info[key][i])
            gaps.terms[key] = max(gaps.terms.get(key, 0.0), abs(mine - value) / (1.0 + abs(value)))
        gaps.terminated_mismatches += int(bool(terminated[i]) != s.terminated)
    return gaps


# ---------------------------------------------------------------------- episode distributions
def ks_two_sample(a, b) -> tuple[float, float]:
    """The two-sample Kolmogorov-Smirnov statistic of ``a`` and ``b`` and its asymptotic p-value."""
    a, b = np.sort(np.asarray(a, np.float64)), np.sort(np.asarray(b, np.float64))
    grid = np.concatenate([a, b])
    cdf_a = np.searchsorted(a, grid, side="right") / a.size
    cdf_b = np.searchsorted(b, grid, side="right") / b.size
    stat = float(np.abs(cdf_a - cdf_b).max())
    m = a.size * b.size / (a.size + b.size)
    lam = (math.sqrt(m) + 0.12 + 0.11 / math.sqrt(m)) * stat
    if lam < 1e-3:
        return stat, 1.0
    p = 2.0 * sum((-1) ** (k - 1) * math.exp(-2.0 * k * k * lam * lam) for k in range(1, 101))
    return stat, float(min(max(p, 0.0), 1.0))


def gymnasium_episodes(task: GymTask, episodes: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Returns and lengths of ``episodes`` uniform-random-action episodes of Gymnasium's env."""
    env = gymnasium_env(task)
    env.action_space.seed(seed)
    returns, lengths = [], []
    for e in range(episodes):
        env.reset(seed=seed + e)
        total, steps, done = 0.0, 0, False
        while not done:
            _, reward, terminated, truncated, _ = env.step(env.action_space.sample())
            total, steps, done = total + reward, steps + 1, terminated or truncated
        returns.append(total)
        lengths.append(steps)
    env.close()
    return np.array(returns), np.array(lengths)


def warpgym_episodes(env: SuiteVecEnv, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Returns and lengths of every world's first episode under uniform random actions (the first of
    each world, not the first to end, which would favour short episodes)."""
    gen = torch.Generator(device=env.device).manual_seed(seed)
    low = torch.as_tensor(env.single_action_space.low, device=env.device)
    high = torch.as_tensor(env.single_action_space.high, device=env.device)
    env.reset(seed=seed)
    returns = torch.zeros(env.num_envs, device=env.device)
    lengths = torch.zeros(env.num_envs, dtype=torch.int32, device=env.device)
    ended = torch.zeros(env.num_envs, dtype=torch.bool, device=env.device)
    for _ in range(env.task.episode_length):
        u = torch.rand(env.num_envs, env.num_actions, device=env.device, generator=gen)
        _, _, terminated, truncated, info = env.step(low + (high - low) * u)
        first = (terminated | truncated) & ~ended
        returns = torch.where(first, info["episode"]["r"], returns)
        lengths = torch.where(first, info["episode"]["l"], lengths)
        ended |= first
        if bool(ended.all()):
            break
    return returns.cpu().numpy().astype(np.float64), lengths.cpu().numpy()


# ---------------------------------------------------------------------- whole episodes, one action sequence
def start_of(task: GymTask, gym_env, obs: np.ndarray) -> tuple:
    """An episode's start in Gymnasium's env, just after its reset: its state in put_states' form (no warm
    start: a reset has none) and its first observation."""
    data = gym_env.unwrapped.data
    return (data.qpos.copy(), data.qvel.copy(), reference_position(task, gym_env), None), obs.copy()


def open_loop_returns(env: SuiteVecEnv, actions: np.ndarray, seeds: list[int]) -> tuple[np.ndarray, np.ndarray]:
    """Returns of one fixed action sequence (``actions``: (steps, U), in the task's units), played from
    Gymnasium's reset states of ``seeds`` in Gymnasium's env and, from the same states, in the first
    worlds of ``env`` (built with ``unit_actions=False``). Without feedback the two can be compared
    episode by episode: a policy's closed loop can part trajectories after any tiny difference (float32
    against float64), as a 1e-7 change to the start does in Gymnasium's own env."""
    gym_env = gymnasium_env(env.task)
    starts, gym_returns = [], []
    for seed in seeds:
        obs, _ = gym_env.reset(seed=seed)
        starts.append(start_of(env.task, gym_env, obs))
        total = 0.0
        for a in actions:
            _, reward, terminated, truncated, _ = gym_env.step(a)
            total += float(reward)
            if terminated or truncated:
                break
        gym_returns.append(total)
    gym_env.close()
    played = iter(torch.as_tensor(np.asarray(actions), dtype=torch.float32, device=env.device))
    ours, _ = warpgym_policy_episodes(env, lambda obs: next(played).expand(env.num_envs, -1), starts,
                                      max_steps=len(actions))
    return np.array(gym_returns), ours


# ---------------------------------------------------------------------- a policy in Gymnasium's env
def gymnasium_policy_episodes(task: str | GymTask, act, episodes: int, seed: int = 0, unit_actions: bool = True,
                              starts: list | None = None, nudge: float = 0.0, terms: dict | None = None,
                              version: int = 5):
    """Returns and lengths of ``episodes`` episodes of ``act`` (a float32 observation batch (1, O) ->
    action batch (1, U), torch, on the CPU) in ``gymnasium.make`` of the task: native MuJoCo, float64,
    episode e reset with seed ``seed + e``. ``unit_actions``: the policy acts in [-1, 1], clipped and
    mapped onto the control range, as ``SuiteVecEnv(unit_actions=True)`` trains it. ``starts``: a list
    that gets each episode's start (its state in put_states' form and its first observation), for
    ``warpgym_policy_episodes`` to play the same episodes. ``nudge``: every start's qpos moved by this much
    (the first action still sees the unmoved observation), to see how far Gymnasium's own returns move
    under a change far below float32's resolution. ``terms``: a dict that gets, for each reward term, the
    list of its episode sums. ``version=4``: in Gymnasium's v4 of the task, the policy seeing the part of
    v4's observation that is v5's (its info holds fewer terms, some under other names: those it lacks under
    v5's names are left out)."""
    task = get_suite_task(task)
    if version != 5 and (starts is not None or nudge):
        raise ValueError("starts and nudge are v5's (warpgym's twin of the env): leave them out with version=4")
    env = gymnasium_env(task, version)
    seen = task.v4_observation if version == 4 else None
    low, high = env.action_space.low.astype(np.float64), env.action_space.high.astype(np.float64)
    returns, lengths = [], []
    names = task.reward_terms()
    with torch.no_grad():
        for e in range(episodes):
            obs, _ = env.reset(seed=seed + e)
            if nudge:
                data = env.unwrapped.data
                env.unwrapped.set_state(data.qpos + nudge, data.qvel.copy())
            if starts is not None:
                starts.append(start_of(task, env, obs))
            total, steps, done, sums = 0.0, 0, False, dict.fromkeys(names, 0.0)
            while not done:
                a = act(torch.as_tensor(obs[:seen], dtype=torch.float32)[None])[0].double().numpy()
                if unit_actions:
                    a = low + (np.clip(a, -1.0, 1.0) + 1.0) * 0.5 * (high - low)
                obs, reward, terminated, truncated, info = env.step(a)
                total, steps, done = total + float(reward), steps + 1, terminated or truncated
                for name in names:
                    sums[name] += float(info.get(name, math.nan))
            returns.append(total)
            lengths.append(steps)
            if terms is not None:
                for name in names:
                    if not math.isnan(sums[name]):
                        terms.setdefault(name, []).append(sums[name])
    env.close()
    return np.array(returns), np.array(lengths)


def warpgym_policy_episodes(env: SuiteVecEnv, act, starts: list, max_steps: int | None = None,
                            terms: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Returns and lengths of the episodes of ``starts`` (``start_of``'s, as ``gymnasium_policy_episodes``
    collects them) played by ``act`` (observation batch -> action batch, on ``env``'s device) in the first
    worlds of ``env``: the same episodes as in Gymnasium's env, so that the two envs' returns differ by the
    simulators alone and not by which starts each drew (Reacher's return, for one, is mostly its target's
    distance). ``max_steps``: stop there, episodes still running counting what they have. ``terms``: a
    dict that gets, for each reward term, the list of its episode sums."""
    n = len(starts)
    if env.num_envs < n:
        raise ValueError(f"{n} episodes need num_envs >= {n}, got {env.num_envs}")
    env.reset(seed=0)
    put_states(env, [state for state, _ in starts])
    obs = torch.zeros(env.num_envs, env.num_obs, device=env.device)
    obs[:n] = torch.as_tensor(np.stack([o for _, o in starts]), dtype=torch.float32, device=env.device)
    returns, lengths = torch.zeros(n, device=env.device), torch.zeros(n, device=env.device)
    names = env.task.reward_terms()
    sums = torch.zeros(len(names), n, device=env.device)
    live = torch.ones(n, dtype=torch.bool, device=env.device)
    with torch.no_grad():
        steps = 0
        while bool(live.any()) and (max_steps is None or steps < max_steps):
            steps += 1
            obs, reward, terminated, truncated, info = env.step(act(obs))
            returns += torch.where(live, reward[:n], torch.zeros_like(reward[:n]))
            if names:
                sums += torch.stack([info[name][:n] for name in names]) * live
            lengths += live.float()
            live &= ~(terminated[:n] | truncated[:n])
    if terms is not None:
        for i, name in enumerate(names):
            terms.setdefault(name, []).extend(sums[i].cpu().double().tolist())
    return returns.cpu().numpy().astype(np.float64), lengths.cpu().numpy().astype(np.float64)
