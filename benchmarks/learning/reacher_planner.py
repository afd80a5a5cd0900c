"""Reacher-v5: the return a controller that knows the model gets, in Gymnasium's own env.

    python -m benchmarks.learning.reacher_planner --out OUT                      # the learning table's 30 episodes
    python -m benchmarks.learning.reacher_planner --out OUT --rounds 10 30 --polish 100 --episodes 3 --seeds 0
    python -m benchmarks.learning.reacher_planner --report OUT/reacher_planner.json

Tianshou's figure for Reacher (-2.6) was made on v2, whose reward counted the distance before each step; v5
counts it after. Whether a policy can reach it in v5 is a question about the task, not the learner, so this
script asks a controller with everything a learner lacks: MuJoCo's model of the env (``gymnasium.make``'s own
MjModel), the exact start state, and all the time it needs. Reacher-v5 has no noise after its reset, so a plan
made from the start state is the episode: for each episode the script optimises the whole sequence of 50 actions
by the cross-entropy method, every candidate simulated by ``mujoco.rollout`` on that model from the start state
(two MuJoCo steps an action, as the env's frame_skip), scored by v5's reward (the fingertip's distance to the
target after the step, plus the squared action). The best plan is then played in ``gymnasium.make("Reacher-v5")``
and its return is what the env pays; the planner's prediction of the return is checked against the env's (within
0.02: the planner reads the fingertip at the end of each step, the env at RK4's last stage), so the model it
optimised is the env's.

The return it finds is one the task allows; a better optimiser could only find more. Each budget of --rounds and --polish is
played, so that the table shows whether more search still pays. Episodes: reset seeds 1000 s + e (e < --episodes)
for s in --seeds, the episodes ``warpgym eval`` and the learning table score. Writes OUT/reacher_planner.json.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

from benchmarks.harness import read_report, reported, write_json

STEPS = 50  # Reacher-v5's TimeLimit
PUBLISHED = -2.6  # Tianshou's PPO, Reacher-v2
KNOTS = 10  # the cross-entropy method's actions per episode (--knots)
PREDICTION_GAP = 0.02  # the planner's return against the env's: RK4's reading of the fingertip, about 1e-4 a step


class Planner:
    """The cross-entropy method over a whole episode's actions, on the env's own MjModel."""

    def __init__(self, env, samples: int, elites: int, threads: int, seed: int, knots: int = KNOTS):
        import mujoco  # noqa: PLC0415
        from mujoco import rollout  # noqa: PLC0415

        self.mujoco, self.env = mujoco, env.unwrapped
        self.model = self.env.model
        self.frame_skip = self.env.frame_skip
        self.spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        self.nstate = mujoco.mj_stateSize(self.model, self.spec)
        self.datas = [mujoco.MjData(self.model) for _ in range(threads)]
        self.runner = rollout.Rollout(nthread=threads)
        self.samples, self.elites, self.knots = samples, elites, knots
        self.rng = np.random.default_rng(seed)
        # where qpos lies in the full physics state: after the time
        self.qpos = slice(1, 1 + self.model.nq)
        body = {mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_BODY, i): i for i in range(self.model.nbody)}
        self.tip, self.target = body["fingertip"], body["target"]
        self.weights = (self.env._reward_dist_weight, self.env._reward_control_weight)
        self._check_kinematics()

    def start_state(self) -> np.ndarray:
        state = np.empty(self.nstate)
        self.mujoco.mj_getState(self.model, self.env.data, state, self.spec)
        return state

    def tip_to_target(self, qpos: np.ndarray) -> np.ndarray:
        """Distances fingertip-target for a batch of qpos: the arm is two hinges about z and the target two slides,
        so the positions are a few products with the model's body offsets (``_check_kinematics`` holds them to
        MuJoCo's own ``mj_kinematics``)."""
        pos = self.model.body_pos
        a, b = qpos[:, 0], qpos[:, 0] + qpos[:, 1]
        tip = pos[self.tip - 2, :2] + np.stack([pos[self.tip - 1, 0] * np.cos(a) + pos[self.tip, 0] * np.cos(b),
                                                pos[self.tip - 1, 0] * np.sin(a) + pos[self.tip, 0] * np.sin(b)], -1)
        target = pos[self.target, :2] + qpos[:, 2:4] - self.model.qpos0[2:4]  # a slide moves from its qpos0
        return np.linalg.norm(tip - target, axis=-1)

    def _check_kinematics(self) -> None:
        """The closed form above against MuJoCo's kinematics on random poses (z is level: both bodies' heights
        are the model's 0.01)."""
        data = self.datas[0]
        qpos = self.rng.uniform(-3.0, 3.0, (64, self.model.nq))
        mine = self.tip_to_target(qpos)
        for q, d in zip(qpos, mine):
            data.qpos[:] = q
            self.mujoco.mj_kinematics(self.model, data)
            truth = np.linalg.norm(data.xpos[self.tip] - data.xpos[self.target])
            if abs(truth - d) > 1e-9:
                raise SystemExit(f"the planner's kinematics give {d} where MuJoCo gives {truth}: this Reacher's "
                                 "model is not the two-hinge arm the planner assumes")

    def rewards(self, start: np.ndarray, plans: np.ndarray) -> np.ndarray:
        """(N, STEPS) v5 rewards of N plans of (STEPS, 2) actions from ``start``, the fingertip read in the state
        after each action's frame_skip steps.

        The env reads the bodies' positions after ``do_simulation``, and Reacher integrates with RK4, whose
        step leaves them at its last stage's state rather than the step's end: the planner's distance differs from
        the env's by about 1e-4 a step. The planner optimises its own reading; what the table reports is what the env pays."""
        n = len(plans)
        control = np.repeat(plans, self.frame_skip, axis=1)  # (N, STEPS * frame_skip, 2)
        state, _ = self.runner.rollout([self.model] * n, self.datas, np.tile(start, (n, 1)), control)
        seen = state[:, self.frame_skip - 1::self.frame_skip, self.qpos]
        dist = self.tip_to_target(seen.reshape(-1, self.model.nq)).reshape(n, STEPS)
        return -self.weights[0] * dist - self.weights[1] * np.square(plans).sum(-1)

    def plan(self, start: np.ndarray, rounds: list[int], polish: list[int]) -> dict[str, np.ndarray]:
        """The best plan found after each of ``rounds`` (sorted) rounds of the cross-entropy method, then after
        each of ``polish`` (sorted) steps of gradient ascent from the method's last plan; keyed "cem N" and
        "cem N + grad M"."""
        # the method searches a few actions (knots), linearly joined over the episode: 20 numbers where a whole
        # plan has 100, which it could not rank well with a few hundred samples; the gradient may refine all 100
        mean, std = np.zeros((self.knots, 2)), np.full((self.knots, 2), 0.5)
        best, best_return, kept = np.zeros((STEPS, 2)), -np.inf, {}
        best_knots = mean.copy()
        for k in range(1, max(rounds) + 1):
            knots = np.clip(mean + std * self.rng.standard_normal((self.samples, self.knots, 2)), -1.0, 1.0)
            knots[0] = best_knots  # the best so far competes again, so a round never loses it
            plans = joined(knots)
            totals = self.rewards(start, plans).sum(1)
            order = np.argsort(-totals)
            if totals[order[0]] > best_return:
                best, best_return, best_knots = plans[order[0]].copy(), totals[order[0]], knots[order[0]].copy()
            elite = knots[order[:self.elites]]
            mean = 0.8 * elite.mean(0) + 0.2 * mean
            std = np.maximum(0.8 * elite.std(0) + 0.2 * std, 0.01)
            if k in rounds:
                kept[f"cem {k}"] = best.copy()
        head = f"cem {max(rounds)}"
        x, m, v = best.copy(), np.zeros_like(best), np.zeros_like(best)
        for k in range(1, max(polish, default=0) + 1):
            total, grad = self.gradient(start, x)
            if total > best_return:
                best, best_return = x.copy(), total
            # Adam, projected onto the action box
            m, v = 0.9 * m + 0.1 * grad, 0.999 * v + 0.001 * grad ** 2
            step = 0.02 * (m / (1 - 0.9 ** k)) / (np.sqrt(v / (1 - 0.999 ** k)) + 1e-8)
            x = np.clip(x + step, -1.0, 1.0)
            if k in polish:
                kept[f"{head} + grad {k}"] = best.copy()
        return kept

    def gradient(self, start: np.ndarray, plan: np.ndarray, h: float = 1e-5) -> tuple[float, np.ndarray]:
        """The plan's return and its gradient by forward differences: 101 rollouts in one batch."""
        n = plan.size
        plans = np.concatenate([plan[None], plan[None] + np.eye(n).reshape(n, STEPS, 2) * h])
        totals = self.rewards(start, plans).sum(1)
        return float(totals[0]), ((totals[1:] - totals[0]) / h).reshape(STEPS, 2)


def joined(knots: np.ndarray) -> np.ndarray:
    """(N, K, 2) actions at K evenly spaced steps -> (N, STEPS, 2) plans, linear between them."""
    k = knots.shape[1]
    at = np.linspace(0, k - 1, STEPS)
    low = np.minimum(at.astype(int), k - 2)
    w = (at - low)[None, :, None]
    return knots[:, low] * (1 - w) + knots[:, low + 1] * w


def play(env, plan: np.ndarray) -> tuple[float, list[float]]:
    """The plan's actions in the env as it stands after its reset: the return and each step's reward."""
    rewards = []
    for a in plan:
        _, r, terminated, truncated, _ = env.step(a)
        rewards.append(float(r))
        if terminated or truncated:
            break
    return sum(rewards), rewards


def run(args) -> dict:
    import gymnasium as gym  # noqa: PLC0415

    env = gym.make("Reacher-v5")
    planner = Planner(env, args.samples, args.elites, args.threads, args.plan_seed, args.knots)
    rounds = sorted(set(args.rounds))
    rows = []
    for seed in args.seeds:
        for e in range(args.episodes):
            reset_seed = 1000 * seed + e
            started = time.time()
            env.reset(seed=reset_seed)
            start = planner.start_state()
            plans = planner.plan(start, rounds, sorted(set(args.polish)))
            row = {"reset_seed": reset_seed, "plan_s": round(time.time() - started, 1), "returns": {}}
            for k, p in plans.items():
                predicted = planner.rewards(start, p[None])[0]
                env.reset(seed=reset_seed)
                total, got = play(env, p)
                gap = abs(total - float(predicted[:len(got)].sum()))
                if len(got) != STEPS or gap > PREDICTION_GAP:
                    raise SystemExit(f"episode {reset_seed}: the env paid {total:.6f} over {len(got)} steps where "
                                     f"the plan predicted {predicted.sum():.6f}: the planner's model is not the env's")
                row["returns"][k] = round(total, 4)
                row["largest_gap"] = max(row.get("largest_gap", 0.0), gap)
            rows.append(row)
            print(json.dumps(row), flush=True)
    return {"argv": sys.argv[1:], "date": time.strftime("%Y-%m-%d"), "gymnasium": gym.__version__,
            "mujoco": planner.mujoco.__version__, "samples": args.samples, "elites": args.elites, "knots": args.knots,
            "stages": list(plans), "rows": rows}


def report(path: str) -> str:
    data = read_report(path, "the reacher_planner.json a run of this script wrote")
    rows = data["rows"]
    lines = [f"Reacher-v5 in gymnasium {data['gymnasium']} (MuJoCo {data['mujoco']}), {len(rows)} episodes "
             f"(reset seeds {rows[0]['reset_seed']}-{rows[-1]['reset_seed']}), the cross-entropy method with "
             f"{data['samples']} plans a round, {data['elites']} elites, {data.get('knots', KNOTS)} knots, {data['date']}", "",
             "| search | return: mean | median | lowest | highest | Tianshou's -2.6 reached |",
             "|---:|---:|---:|---:|---:|---|"]
    for k in data["stages"]:
        r = [row["returns"][k] for row in rows]
        lines.append(f"| {k} | {statistics.mean(r):.2f} | {statistics.median(r):.2f} | {min(r):.2f} | {max(r):.2f} | "
                     f"{sum(x >= PUBLISHED for x in r)} of {len(r)} episodes |")
    gap = max(row["largest_gap"] for row in rows)
    lines += ["", f"The planner's predicted return against the env's: largest difference {gap:.1e}."]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="folder for reacher_planner.json")
    ap.add_argument("--report", metavar="JSON", help="print the table of an earlier run and stop")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2], help="reset seeds, as warpgym eval's")
    ap.add_argument("--episodes", type=int, default=10, help="episodes per seed (default 10)")
    ap.add_argument("--rounds", type=int, nargs="+", default=[30, 60, 120],
                    help="rounds of the cross-entropy method after which the best plan is played (default 30 60 120)")
    ap.add_argument("--polish", type=int, nargs="*", default=[],
                    help="steps of gradient ascent (forward differences) after the last round, after which the best "
                         "plan is played (default none: from the method's plans, whose actions sit on the bounds, "
                         "it found no step up)")
    ap.add_argument("--knots", type=int, default=KNOTS,
                    help=f"actions a plan is drawn through, joined linearly over the {STEPS} steps (default {KNOTS}; "
                         f"{STEPS}: every action free)")
    ap.add_argument("--samples", type=int, default=512, help="plans a round (default 512)")
    ap.add_argument("--elites", type=int, default=32, help="best plans a round keeps (default 32)")
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--plan-seed", type=int, default=0, help="the planner's own random numbers")
    args = ap.parse_args(argv)
    if reported(ap, args, report, "JSON"):
        return 0
    if min(args.rounds) < 1 or any(k < 0 for k in args.polish) or args.episodes < 1 or not 1 <= args.elites < args.samples \
            or not 2 <= args.knots <= STEPS:
        ap.error(f"--rounds {args.rounds} --polish {args.polish} --episodes {args.episodes} --elites {args.elites} --samples "
                 f"{args.samples} --knots {args.knots}: need rounds and episodes of at least 1, no negative polish, fewer "
                 f"elites than plans, and 2 to {STEPS} knots")
    os.makedirs(args.out, exist_ok=True)
    data = run(args)
    path = os.path.join(args.out, "reacher_planner.json")
    write_json(path, data)
    print(report(path))
    return 0


if __name__ == "__main__":
    sys.exit(main())
