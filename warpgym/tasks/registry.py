"""Every task warpgym runs, every family in one table, with what the commands need of each as callables.

- **robots**: warpgym's own Ant and Humanoid (Newton's model, Isaac Gym's task definitions,
  ``LocomotionVecEnv``), scored in native MuJoCo (``warpgym eval``, ``warpgym sim2sim``).
- **suite**: Gymnasium's MuJoCo tasks (MuJoCo's compile of Gymnasium's model file, ``SuiteVecEnv``),
  scored in ``gymnasium.make``'s env (``warpgym eval``).
- **legged**: legged robots following a velocity command as mjlab defines them (MuJoCo's compile of mjlab's scene,
  ``LeggedVecEnv``), checked against mjlab's own env (tests/test_legged_judge.py).

``make_vec_env``, the Gymnasium ids, ``warpgym train`` (its preset), ``play``, ``eval`` (``evaluate``), ``export``
(``export_contract``) and the command line's task list read a task's entry here; no other module asks which family
a name belongs to (tests/test_layout.py). Env classes are named as Gymnasium's registry names them, by entry point,
and the commands' functions import their modules when called (``_command``), so this layer imports nothing above
it. ``register`` enters a user's own task (a legged task with terms of its own) under its family's contract.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Callable

from warpgym.tasks.robots import TASKS as ROBOTS
from warpgym.tasks.robots import LocomotionTask
from warpgym.tasks.legged import LEGGED, LeggedTask
from warpgym.tasks.legged.contract import deployment_contract
from warpgym.tasks.names import imported
from warpgym.tasks.presets import LEGGED as LEGGED_PRESET
from warpgym.tasks.presets import PRESETS, SAC_LEGGED, SAC_ROBOTS, SAC_SUITE
from warpgym.tasks.suite import SUITE, GymTask


@dataclass(frozen=True)
class TaskEntry:
    name: str  # as the command line and the checkpoints write it: "Ant", "Hopper-v5"
    family: str  # "robots", "suite" or "legged"
    gym_id: str  # gymnasium.make's id: "warpgym/Ant-v0", "warpgym/Hopper-v5"
    episode_length: int  # control steps to the time limit
    vector_entry_point: str
    single_entry_point: str
    # keyword arguments of the env a learner trains on: the suite's policies act in [-1, 1], mapped onto
    # the control ranges; the robots' envs always act in [-1, 1]
    learner_kwargs: tuple[tuple[str, object], ...]
    physics_flags: bool  # warpgym's own physics settings (--substeps, --physics) apply
    # the state a clip records each step (media.clips.StateRecorder's keys; empty: the robot's whole state)
    # and whether it draws every world or the first (the suite's clips use Gymnasium's renderer, one world)
    clip_keys: tuple[str, ...]
    clip_all_worlds: bool
    draw_clip: Callable  # draws a recorded clip (warpgym.media.<family>): (env, states, outputs, width, height)
    training_clips: bool  # `warpgym train --video` can film its evaluations (media.clips draws the robots only)
    scored_in: str  # "native MuJoCo" or "Gymnasium's env": where `warpgym eval` plays a trained policy
    reports_speed: bool  # the env's forward speed is the task's measure (eval/speed beside eval/return)
    # `warpgym train`'s default envs and iterations on a GPU and on the CPU (docs/benchmarks.md, "Envs per GPU")
    default_envs: tuple[int, int]
    default_iterations: tuple[int, int]
    preset: dict = None  # PPO's starting point (agents.Config fields, warpgym.tasks.presets)
    sac_preset: dict = None  # the off-policy learner's (agents.sac.SACConfig fields; `warpgym train --algo sac`)
    # the commands' parts that differ by family, as callables (each imports its module when called:
    # ``_command``): how `warpgym eval` scores a policy, and what `warpgym export` writes about the task (None: the
    # env's own observation and action, docs/tasks.md)
    evaluate: Callable = None
    export_contract: Callable | None = None
    # `warpgym bench --tasks`: (name, num_envs, device, steps, warmup, repeats, njmax) -> a row of the task's step
    # beside MuJoCo Warp's own (env_steps_per_s, mjwarp_steps_per_s: a median or each timing)
    bench: Callable = None
    asymmetric: bool = False  # the critic has an observation group of its own (info["critic_obs"])

    def preset_for(self, algo: str) -> dict:
        """The starting point of a learner (agents.algos' names) on this task."""
        return self.sac_preset if algo == "sac" else self.preset

    def defaults(self, device_kind: str) -> tuple[int, int]:
        """(envs, iterations) for a device kind, "cuda" or "cpu"."""
        k = 0 if device_kind == "cuda" else 1
        return self.default_envs[k], self.default_iterations[k]


def _command(module: str, name: str) -> Callable:
    """A command's function, imported when it is called: the contract holds callables, and this layer loads
    nothing above it until a command calls one."""
    def call(*args, **kwargs):
        return getattr(importlib.import_module(module), name)(*args, **kwargs)

    call.__qualname__ = call.__name__ = f"{module}.{name}"
    return call


def _robot(name: str, episode_length: int, envs: tuple[int, int], iterations: tuple[int, int],
           preset: str | None = None) -> TaskEntry:
    return TaskEntry(name, "robots", f"warpgym/{name}-v0", episode_length,
                     "warpgym.envs.robots:LocomotionVecEnv", "warpgym.envs.robots:LocomotionEnv", (),
                     physics_flags=True, clip_keys=(), clip_all_worlds=True,
                     draw_clip=_command("warpgym.media.robots", "draw_robot_clip"), training_clips=True,
                     scored_in="native MuJoCo",
                     reports_speed=True, default_envs=envs, default_iterations=iterations,
                     preset=PRESETS[preset or name], sac_preset=SAC_ROBOTS,
                     evaluate=_command("warpgym.cli.eval.robots", "evaluate"),
                     bench=_command("warpgym.cli.bench.robots", "bench_robot_task"))


def _suite(name: str, episode_length: int, preset: str | None = None) -> TaskEntry:
    return TaskEntry(name, "suite", f"warpgym/{name}", episode_length,
                     "warpgym.envs.suite:SuiteVecEnv", "warpgym.envs.suite:SuiteEnv", (("unit_actions", True),),
                     physics_flags=False, clip_keys=("dof_pos", "dof_vel"), clip_all_worlds=False,
                     draw_clip=_command("warpgym.media.suite", "draw_suite_clip"), training_clips=False,
                     scored_in="Gymnasium's env", reports_speed=False, default_envs=(4096, 64),
                     default_iterations=(500, 100), preset=PRESETS[preset or name], sac_preset=SAC_SUITE,
                     evaluate=_command("warpgym.cli.eval.suite", "evaluate"),
                     bench=_command("warpgym.cli.bench.suite", "bench_suite_task"))


def _legged(name: str, episode_length: int) -> TaskEntry:
    # mjlab trains its velocity tasks with 4096 envs; a legged task a user registers trains with mjlab's settings
    return TaskEntry(name, "legged", f"warpgym/{name}", episode_length,
                     "warpgym.envs.legged:LeggedVecEnv", "warpgym.envs.legged:LeggedEnv", (),
                     physics_flags=False, clip_keys=("dof_pos", "dof_vel"), clip_all_worlds=False,
                     draw_clip=_command("warpgym.media.legged", "draw_legged_clip"), training_clips=False,
                     scored_in="native MuJoCo", reports_speed=False, default_envs=(4096, 32),
                     default_iterations=(1000, 30), preset=PRESETS.get(name, LEGGED_PRESET), sac_preset=SAC_LEGGED,
                     evaluate=_command("warpgym.cli.eval.legged", "evaluate"),
                     export_contract=deployment_contract, asymmetric=True,
                     bench=_command("warpgym.cli.bench.legged", "bench_legged_task"))


# 8192 Ants and 4096 Humanoids reach their targets soonest on one H100 (docs/benchmarks.md, "Envs per GPU");
# on a 2-core CPU the Ant's default trains for about 50 s, enough to see it learn
REGISTRY: dict[str, TaskEntry] = {
    "Ant": _robot("Ant", ROBOTS["ant"].episode_length, (8192, 64), (500, 200)),
    "Humanoid": _robot("Humanoid", ROBOTS["humanoid"].episode_length, (4096, 64), (1000, 20)),
    **{name: _suite(name, task.episode_length) for name, task in SUITE.items()},
    **{name: _legged(name, task.episode_length) for name, task in LEGGED.items()},
}


BUILT_IN = frozenset(REGISTRY)


def task_entry(name: str) -> TaskEntry:
    """The entry of a task name, as written or in any letter case ("hopper-v5"), or ``"module:Name"`` (the module
    imported first, as Gymnasium's ``make`` imports it)."""
    name = imported(name)
    if name in REGISTRY:
        return REGISTRY[name]
    by_lower = {n.lower(): e for n, e in REGISTRY.items()}
    if str(name).lower() in by_lower:
        return by_lower[str(name).lower()]
    raise ValueError(f"unknown task {name!r}: choose one of {', '.join(REGISTRY)}")


def canonical(name: str) -> str:
    """A task name as a run records it: the registry's spelling, ``module:Name`` kept for a user's task (a replay
    imports the module again)."""
    entry = task_entry(name)
    module = name.partition(":")[0] if isinstance(name, str) and ":" in name else ""
    return f"{module}:{entry.name}" if module else entry.name


def task_names(family: str | None = None) -> list[str]:
    """Every task's name, or one family's ("robots", "suite", "legged")."""
    if family not in (None, "robots", "suite", "legged"):
        raise ValueError(f"family={family!r}: choose robots, suite or legged")
    return [n for n, e in REGISTRY.items() if family in (None, e.family)]


def register(task) -> object:
    """A task of the user's own (a task's ``replace`` with a new ``name``, say, its own terms in its tables) entered
    as warpgym's own: in the registry under its family's contract, as the Gymnasium id ``warpgym/<name>``, and by
    name for ``warpgym train --task module:<name>``, play, eval and export (a suite task is judged in Gymnasium's env
    of the task it changes; a robot's, with the preset and defaults of the built-in task of its robot). Returns the
    task. Call it from the module that defines the task; naming a task warpgym has is refused."""
    import gymnasium as gym  # noqa: PLC0415

    if not isinstance(task, (LeggedTask, GymTask, LocomotionTask)):
        raise TypeError(f"register({task!r}): a task of one of the families (a LeggedTask, a GymTask or a "
                        "LocomotionTask), made by a built-in task's replace(name=..., ...)")
    name = task.name
    if name in BUILT_IN or name.lower() in {n.lower() for n in BUILT_IN}:
        raise ValueError(f"register: {name!r} is warpgym's own task: give yours a name of its own "
                         f"(task.replace(name='My{name}', ...))")
    task.validate()
    if isinstance(task, LocomotionTask):
        like = next(REGISTRY[n] for n in BUILT_IN if REGISTRY[n].family == "robots"
                    and ROBOTS[n.lower()].robot == task.robot)
        ROBOTS[name.lower()] = task
        entry = REGISTRY[name] = _robot(name, task.episode_length, like.default_envs, like.default_iterations,
                                        preset=like.name)
    elif isinstance(task, GymTask):
        SUITE[name] = task
        entry = REGISTRY[name] = _suite(name, task.episode_length, preset=task.gymnasium_id)
    else:
        LEGGED[name] = task
        entry = REGISTRY[name] = _legged(name, task.episode_length)
    gym.registry.pop(entry.gym_id, None)
    gym.register(id=entry.gym_id, entry_point=entry.single_entry_point, vector_entry_point=entry.vector_entry_point,
                 max_episode_steps=entry.episode_length, kwargs={"task": name})
    return task


__all__ = ["REGISTRY", "TaskEntry", "canonical", "register", "task_entry", "task_names"]
