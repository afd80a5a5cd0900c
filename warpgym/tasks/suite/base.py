"""What every task of Gymnasium's MuJoCo suite shares: its model file, frame skip and time limit,
Gymnasium's constructor arguments as fields (their defaults are Gymnasium v5's), and how those
become the kernels' ``GymParams``.

One file per task beside this one holds its fields and ``fill_params``; the kernels
(``kernels/suite/step.py``, ``kernels/suite/resets.py``) hold the step itself. A task's own terms beside
Gymnasium's (``rewards``, ``terminations``: tables of ``warpgym.tasks.terms``, empty in Gymnasium's tasks) run in
the same step; Gymnasium's own env, which judges the suite, knows nothing of them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from typing import ClassVar

from kernels.suite import params as G
from warpgym.tasks.terms import Terms, changed_own_tables, validate_own_tables

INF = math.inf

# Each kind's reward terms in their columns' order, as kernels.suite.params names them
TERM_COLUMNS = {kind: tuple(term.name for term in terms) for kind, terms in G.TERMS.items()}
MAX_TERMS = G.MAX_TERMS

# Fields of a task that are not Gymnasium constructor arguments
OWN_FIELDS = ("name", "episode_length", "nconmax", "njmax", "rewards", "terminations")


@dataclass(frozen=True)
class GymTask:
    name: str
    xml_file: str
    frame_skip: int
    episode_length: int = 1000  # Gymnasium's TimeLimit (max_episode_steps)
    nconmax: int = 32  # contacts and constraint rows per world MuJoCo Warp makes room for
    njmax: int = 128
    # the task's own reward terms (each ``weight * value`` a step, added to Gymnasium's reward and reported as
    # ``info["reward_<name>"]``) and terminations (beside Gymnasium's), over ``kernels.suite.params.SuiteState``
    rewards: Terms = Terms("reward")
    terminations: Terms = Terms("termination")

    kind: ClassVar[int] = G.FORWARD
    info_keys: ClassVar[tuple[str, ...]] = ()  # the reward terms and info entries Gymnasium's step returns
    contact_forces: ClassVar[bool] = False  # reads cfrc_ext: mj_rnePostConstraint after the step
    reset_kinematics: ClassVar[bool] = False  # the first observation or forward position needs body poses
    reset_com: ClassVar[bool] = False  # ... and com inertias and velocities
    has_speed: ClassVar[bool] = False  # a forward speed (info["episode"]["s"])
    # Gymnasium's v4 of the task (gym's v2/v3 definitions on MuJoCo's own bindings, where most published
    # figures come from): how many of its observation's first entries are v5's observation, so that a
    # v5 policy plays it unchanged. None where v4's observation is laid out otherwise (Ant, Humanoid,
    # HumanoidStandup) or v4 refuses MuJoCo 3 (Pusher).
    v4_observation: ClassVar[int | None] = None

    @classmethod
    def reward_terms(cls) -> tuple[str, ...]:
        """The info entries that are terms of the reward, in Gymnasium's names and signs (a cost is
        negative), each step's reward their sum (HumanoidStandup adds 1 a step beside them)."""
        return tuple(k for k in cls.info_keys if k.startswith("reward_") or k.endswith("_penalty"))

    @property
    def camera_follows(self) -> bool:
        """Whether a clip's camera keeps the root body in frame: a runner leaves a fixed camera's frame
        within seconds. A task whose robot moves off without a forward speed sets it as a class attribute."""
        return self.has_speed

    @property
    def gymnasium_id(self) -> str:
        """The Gymnasium task this one is (and is judged in): its class's name, whatever a user's task is called."""
        return type(self).__dataclass_fields__["name"].default

    def version_name(self, version: int) -> str:
        return self.gymnasium_id.rsplit("-v", 1)[0] + f"-v{version}"

    # ------------------------------------------------------------------ Gymnasium's arguments
    @classmethod
    def argument_names(cls) -> list[str]:
        return [f.name for f in fields(cls) if f.name not in OWN_FIELDS]

    def replace(self, **changes) -> GymTask:
        """A copy with Gymnasium constructor arguments (or episode_length, nconmax, njmax) changed; ``rewards`` and
        ``terminations`` take the changes of the terms they name (``warpgym.tasks.terms.Terms.changed``)."""
        names = [f.name for f in fields(self)]
        unknown = sorted(set(changes) - set(names) - {"name"})
        if unknown:
            raise ValueError(f"{self.name} has no argument(s) {unknown}: Gymnasium's {self.name} takes "
                             f"{self.argument_names()} (and warpgym episode_length, nconmax, njmax, and its own "
                             "terms: rewards, terminations)")
        changes = changed_own_tables(self, changes)
        values = {**{n: getattr(self, n) for n in names}, **changes}
        for name, value in values.items():
            default = getattr(type(self), name, None)
            if isinstance(default, tuple) and not isinstance(value, tuple):
                values[name] = tuple(value)
        out = type(self)(**values)
        out.validate()
        return out

    def validate(self) -> None:
        for name in ("frame_skip", "episode_length", "nconmax", "njmax"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{self.name}: {name}={v!r} must be a positive integer")
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name in OWN_FIELDS or f.name in ("xml_file", "frame_skip"):
                continue
            values = v if isinstance(v, tuple) else (v,)
            for x in values:
                if isinstance(x, (int, float)) and not isinstance(x, bool) and math.isnan(x):
                    raise ValueError(f"{self.name}: {f.name}={v!r} holds NaN")
            if isinstance(v, tuple) and (len(v) != 2 or not v[0] <= v[1]):
                raise ValueError(f"{self.name}: {f.name}={v!r} must be a (low, high) range with low <= high")
        validate_own_tables(self)

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def gymnasiums_terms_only(self) -> GymTask:
        """This task without its own terms: Gymnasium's reward and terminations alone, as Gymnasium's env scores it."""
        return replace(self, rewards=Terms("reward"), terminations=Terms("termination"))

    def own_terms(self) -> tuple[str, ...]:
        """The info keys of the task's own reward terms, in its table's order."""
        return tuple(f"reward_{name}" for name in self.rewards)

    # ------------------------------------------------------------------ the kernels' view
    def params(self, sim) -> G.GymParams:
        p = G.GymParams()
        p.kind = self.kind
        p.dt, p.timestep = sim.dt, sim.timestep
        p.episode_length = self.episode_length
        p.qvel_clip, p.cfrc_lo, p.cfrc_hi = INF, -INF, INF
        p.position_source, p.contact_cost_mode = G.POSITION_QPOS_X, G.CONTACT_NONE
        p.contact_lo, p.contact_hi = -INF, INF
        p.healthy_z_index = p.healthy_angle_index = -1
        p.healthy_z_lo, p.healthy_z_hi, p.healthy_angle_lo, p.healthy_angle_hi = -INF, INF, -INF, INF
        p.healthy_state_lo, p.healthy_state_hi = -INF, INF
        p.goal_mode = G.GOAL_NONE
        self.fill_params(p, sim)
        return p

    def fill_params(self, p: G.GymParams, sim) -> None:
        raise NotImplementedError

    def observation_size(self, sim) -> int:
        raise NotImplementedError

    def body(self, sim, name) -> int:
        """A body index: Gymnasium's ``main_body`` may be an index or a name."""
        if isinstance(name, int):
            if not 0 <= name < sim.nbody:
                raise ValueError(f"{self.name}: body index {name} outside [0, {sim.nbody - 1}]")
            return name
        if name not in sim.body_names:
            raise ValueError(f"{self.name}: the model has no body {name!r}; its bodies are {sim.body_names}")
        return sim.body_names.index(name)

    def term_columns(self) -> dict[str, int]:
        columns = TERM_COLUMNS[self.kind]
        return {key: columns.index(key) for key in self.info_keys}


def forward_observation_size(sim, qpos_skip: int, cinert=False, cvel=False, qfrc_actuator=False,
                             cfrc_ext=False) -> int:
    bodies = sim.nbody - 1
    return (sim.nq - qpos_skip + sim.nv + 10 * bodies * cinert + 6 * bodies * cvel + (sim.nv - 6) * qfrc_actuator
            + 6 * bodies * cfrc_ext)


def fill_health(p: G.GymParams, healthy_reward: float, terminate: bool, z_index: int, z_range, inclusive=False,
                angle_range=None, state_range=None, finite=False) -> None:
    p.healthy_reward = float(healthy_reward)
    p.terminate_when_unhealthy = int(bool(terminate))
    p.healthy_z_index = z_index
    p.healthy_z_lo, p.healthy_z_hi = (float(v) for v in z_range)
    p.healthy_z_inclusive = int(inclusive)
    if angle_range is not None:
        p.healthy_angle_index = 2
        p.healthy_angle_lo, p.healthy_angle_hi = (float(v) for v in angle_range)
    if state_range is not None:
        p.healthy_state_lo, p.healthy_state_hi = (float(v) for v in state_range)
    p.healthy_finite = int(finite)
