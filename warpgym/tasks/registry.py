"""Every task warpgym runs, both families in one table.

- **robots**: warpgym's own Ant and Humanoid (Newton's model, Isaac Gym's task definitions,
  ``LocomotionVecEnv``), scored in native MuJoCo (``warpgym eval``, ``warpgym sim2sim``).
- **suite**: Gymnasium's MuJoCo tasks (MuJoCo's compile of Gymnasium's model file, ``SuiteVecEnv``),
  scored in ``gymnasium.make``'s env (``warpgym eval``).
- **legged**: legged robots following a velocity command as mjlab defines them (MuJoCo's compile of mjlab's scene,
  ``LeggedVecEnv``), checked against mjlab's own env (tests/test_legged_judge.py).

``make_vec_env``, the Gymnasium ids, ``warpgym train``, ``play``, ``eval`` and the command line's task
list read a task's entry here; no other module asks which family a name belongs to
(tests/test_layout.py). Env classes are named as Gymnasium's registry names them, by entry point, so
this layer imports nothing above it.
"""

from __future__ import annotations

from dataclasses import dataclass

from warpgym.tasks import TASKS as ROBOTS
from warpgym.tasks.legged import LEGGED
from warpgym.tasks.suite import SUITE


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
    clip_drawer: str  # the function that draws a recorded clip, by entry point (warpgym.media.video)
    training_clips: bool  # `warpgym train --video` can film its evaluations (media.clips draws the robots only)
    scored_in: str  # "native MuJoCo" or "Gymnasium's env": where `warpgym eval` plays a trained policy
    reports_speed: bool  # the env's forward speed is the task's measure (eval/speed beside eval/return)
    # `warpgym train`'s default envs and iterations on a GPU and on the CPU (docs/benchmarks.md, "Envs per GPU")
    default_envs: tuple[int, int]
    default_iterations: tuple[int, int]

    def defaults(self, device_kind: str) -> tuple[int, int]:
        """(envs, iterations) for a device kind, "cuda" or "cpu"."""
        k = 0 if device_kind == "cuda" else 1
        return self.default_envs[k], self.default_iterations[k]


def _robot(name: str, episode_length: int, envs: tuple[int, int], iterations: tuple[int, int]) -> TaskEntry:
    return TaskEntry(name, "robots", f"warpgym/{name}-v0", episode_length,
                     "warpgym.envs.locomotion:LocomotionVecEnv", "warpgym.envs.single:LocomotionEnv", (),
                     physics_flags=True, clip_keys=(), clip_all_worlds=True,
                     clip_drawer="warpgym.media.video:draw_robot_clip", training_clips=True,
                     scored_in="native MuJoCo",
                     reports_speed=True, default_envs=envs, default_iterations=iterations)


def _suite(name: str, episode_length: int) -> TaskEntry:
    return TaskEntry(name, "suite", f"warpgym/{name}", episode_length,
                     "warpgym.envs.suite:SuiteVecEnv", "warpgym.envs.single:SuiteEnv", (("unit_actions", True),),
                     physics_flags=False, clip_keys=("dof_pos", "dof_vel"), clip_all_worlds=False,
                     clip_drawer="warpgym.media.video:draw_suite_clip", training_clips=False,
                     scored_in="Gymnasium's env", reports_speed=False, default_envs=(4096, 64),
                     default_iterations=(500, 100))


def _legged(name: str, episode_length: int) -> TaskEntry:
    # mjlab trains its velocity tasks with 4096 envs
    return TaskEntry(name, "legged", f"warpgym/{name}", episode_length,
                     "warpgym.envs.legged:LeggedVecEnv", "warpgym.envs.single:LeggedEnv", (),
                     physics_flags=False, clip_keys=("dof_pos", "dof_vel"), clip_all_worlds=False,
                     clip_drawer="warpgym.media.video:draw_legged_clip", training_clips=False,
                     scored_in="native MuJoCo", reports_speed=False, default_envs=(4096, 32),
                     default_iterations=(1000, 30))


# 8192 Ants and 4096 Humanoids reach their targets soonest on one H100 (docs/benchmarks.md, "Envs per GPU");
# on a 2-core CPU the Ant's default trains for about 50 s, enough to see it learn
REGISTRY: dict[str, TaskEntry] = {
    "Ant": _robot("Ant", ROBOTS["ant"].episode_length, (8192, 64), (500, 200)),
    "Humanoid": _robot("Humanoid", ROBOTS["humanoid"].episode_length, (4096, 64), (1000, 20)),
    **{name: _suite(name, task.episode_length) for name, task in SUITE.items()},
    **{name: _legged(name, task.episode_length) for name, task in LEGGED.items()},
}


def task_entry(name: str) -> TaskEntry:
    """The entry of a task name, as written or in any letter case ("hopper-v5")."""
    if name in REGISTRY:
        return REGISTRY[name]
    by_lower = {n.lower(): e for n, e in REGISTRY.items()}
    if str(name).lower() in by_lower:
        return by_lower[str(name).lower()]
    raise ValueError(f"unknown task {name!r}: choose one of {', '.join(REGISTRY)}")


def task_names(family: str | None = None) -> list[str]:
    """Every task's name, or one family's ("robots", "suite", "legged")."""
    if family not in (None, "robots", "suite", "legged"):
        raise ValueError(f"family={family!r}: choose robots, suite or legged")
    return [n for n, e in REGISTRY.items() if family in (None, e.family)]


__all__ = ["REGISTRY", "TaskEntry", "task_entry", "task_names"]
