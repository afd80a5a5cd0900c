"""The peer users run today: Stable-Baselines3 PPO on Gymnasium's own env, on the CPU cores of the same host.

Each task and seed trains ``stable_baselines3.PPO`` for --minutes on ``gymnasium.make("<Name>-v5")`` with
the RL Baselines3 Zoo's hyperparameters for the task (``ZOO``: its hyperparams/ppo.yml, tuned on the v4
tasks, whose v5 versions change some observations, Ant's contact forces among them; VecNormalize on observations and rewards, as its ``normalize: true``). The Zoo runs
these with one env, one process: so does this script, each run pinned to one core with one torch thread,
--parallel runs at once. Its policies at the marks (1, 2, 3, 5, 10 minutes of training; 1, 2, 5, 10 before
2026-11-28) are kept in memory and scored after training as suite_learning.py scores warpgym's: the
deterministic policy, 10 episodes from each of 3 seeds in ``gymnasium.make``'s env. Every 30 s of training a deterministic 5-episode
evaluation gives the minutes to the reference; its time, and the snapshots', is kept off the training
clock.

One JSON per run (``OUT/sb3-<task>-seed<k>.json``), in suite_learning.py's form, which its ``--report``
sets beside warpgym's runs.

    python -m benchmarks.learning.suite_sb3 --out OUT --tasks HalfCheetah-v5 Hopper-v5 --seeds 0 1 --parallel 4
"""

from __future__ import annotations

import argparse
import copy
import json
import os
import subprocess
import sys
import time

from benchmarks.learning.suite_learning import MARKS, half, thin  # noqa: E402
from benchmarks.targets import REFERENCE  # noqa: E402

_RELU_256 = dict(log_std_init=-2.0, ortho_init=False, activation_fn="relu", net_arch=dict(pi=[256, 256], vf=[256, 256]))
# rl-baselines3-zoo, hyperparams/ppo.yml (the v4 entries; Ant-v4 takes its MuJoCo defaults: SB3's PPO defaults)
ZOO: dict[str, dict] = {
    "HalfCheetah-v5": dict(batch_size=64, n_steps=512, gamma=0.98, learning_rate=2.0633e-05, ent_coef=0.000401762,
                           clip_range=0.1, n_epochs=20, gae_lambda=0.92, max_grad_norm=0.8, vf_coef=0.58096,
                           policy_kwargs=_RELU_256),
    "Hopper-v5": dict(batch_size=32, n_steps=512, gamma=0.999, learning_rate=9.80828e-05, ent_coef=0.00229519,
                      clip_range=0.2, n_epochs=5, gae_lambda=0.99, max_grad_norm=0.7, vf_coef=0.835671,
                      policy_kwargs=_RELU_256),
    "Walker2d-v5": dict(batch_size=32, n_steps=512, gamma=0.99, learning_rate=5.05041e-05, ent_coef=0.000585045,
                        clip_range=0.1, n_epochs=20, gae_lambda=0.95, max_grad_norm=1.0, vf_coef=0.871923),
    "Ant-v5": dict(),
    "Humanoid-v5": dict(batch_size=256, n_steps=512, gamma=0.95, learning_rate=3.56987e-05, ent_coef=0.00238306,
                        clip_range=0.3, n_epochs=5, gae_lambda=0.9, max_grad_norm=2.0, vf_coef=0.431892,
                        policy_kwargs=_RELU_256),
    "Swimmer-v5": dict(gamma=0.9999, n_steps=1024, batch_size=256, learning_rate=6e-4, gae_lambda=0.98, n_envs=4),
}
EVAL_GAP_S = 30.0
EVAL_SEEDS = (0, 1, 2)  # as suite_learning.py scores warpgym's policies


def hyperparameters(task: str) -> tuple[dict, int]:
    """The Zoo's PPO keyword arguments for the task, as SB3 takes them, and its number of envs."""
    import torch  # noqa: PLC0415

    if task not in ZOO:
        raise ValueError(f"no RL Zoo hyperparameters for {task!r} here: choose from {list(ZOO)}")
    kw = copy.deepcopy(ZOO[task])
    n_envs = kw.pop("n_envs", 1)
    if "policy_kwargs" in kw:
        kw["policy_kwargs"]["activation_fn"] = {"relu": torch.nn.ReLU}[kw["policy_kwargs"]["activation_fn"]]
    return kw, n_envs


class _Clock:
    """Training time: wall time less what evaluation and snapshots took."""

    def __init__(self):
        self.start, self.paused = time.perf_counter(), 0.0

    def now(self) -> float:
        return time.perf_counter() - self.start - self.paused

    def pause(self, seconds: float):
        self.paused += seconds


def _deterministic_act(model, mean, var, clip):
    import numpy as np  # noqa: PLC0415
    import torch  # noqa: PLC0415

    def act(obs):
        o = np.clip((obs.double().numpy() - mean) / np.sqrt(var + 1e-8), -clip, clip).astype(np.float32)
        return torch.as_tensor(model.policy.predict(o, deterministic=True)[0])  # clipped to the action bounds
    return act


def train_one(task: str, seed: int, minutes: float, marks: tuple[float, ...], eval_episodes: int) -> dict:
    import numpy as np  # noqa: PLC0415
    import torch  # noqa: PLC0415
    from stable_baselines3 import PPO  # noqa: PLC0415
    from stable_baselines3.common.callbacks import BaseCallback  # noqa: PLC0415
    from stable_baselines3.common.env_util import make_vec_env  # noqa: PLC0415
    from stable_baselines3.common.vec_env import VecNormalize  # noqa: PLC0415

    from warpgym.native.suite import gymnasium_policy_episodes  # noqa: PLC0415

    torch.set_num_threads(1)
    kw, n_envs = hyperparameters(task)
    venv = VecNormalize(make_vec_env(task, n_envs=n_envs, seed=seed), gamma=kw.get("gamma", 0.99))
    model = PPO("MlpPolicy", venv, seed=seed, device="cpu", verbose=0, **kw)
    budget = minutes * 60.0
    clock = _Clock()
    curve, evals, kept = [], [], []

    def snapshot():
        return (copy.deepcopy(model.policy.state_dict()), venv.obs_rms.mean.copy(), venv.obs_rms.var.copy())

    def score(snap, episodes, seed0):
        state, mean, var = snap
        live = copy.deepcopy(model.policy.state_dict())
        model.policy.load_state_dict(state)
        r, _ = gymnasium_policy_episodes(task, _deterministic_act(model, mean, var, venv.clip_obs), episodes,
                                         seed=seed0, unit_actions=False)
        model.policy.load_state_dict(live)
        return float(r.mean())

    class Marks(BaseCallback):
        def __init__(self):
            super().__init__()
            self.next_eval, self.marks = 0.0, list(marks)

        def _on_step(self) -> bool:
            t = clock.now()
            for info in self.locals["infos"]:
                if "episode" in info:
                    curve.append((round(t, 3), self.num_timesteps, float(info["episode"]["r"])))
            if t >= self.next_eval:
                t0 = time.perf_counter()
                evals.append({"time_s": t, "samples": self.num_timesteps,
                              "eval/return": score(snapshot(), 5, 10_000 + len(evals))})
                self.next_eval += EVAL_GAP_S
                clock.pause(time.perf_counter() - t0)
            while self.marks and t >= self.marks[0]:
                t0 = time.perf_counter()
                kept.append({"mark_s": self.marks.pop(0), "time_s": t, "samples": self.num_timesteps,
                             "snap": snapshot()})
                clock.pause(time.perf_counter() - t0)
            return t < budget

    model.learn(total_timesteps=10**12, callback=Marks())
    samples, train_s = int(model.num_timesteps), clock.now()
    scored = []
    for k in kept:
        state, mean, var = k.pop("snap")
        model.policy.load_state_dict(state)
        act = _deterministic_act(model, mean, var, venv.clip_obs)
        # the episodes warpgym eval --seeds 0 1 2 plays: resets seeded 0.., 1000.., 2000..
        r = np.concatenate([gymnasium_policy_episodes(task, act, eval_episodes, seed=1000 * s, unit_actions=False)[0]
                            for s in EVAL_SEEDS])
        scored.append({**k, "gymnasium_return": float(np.mean(r)), "episodes": int(r.size)})
    venv.close()
    return {"task": task, "seed": seed, "budget_s": budget, "marks_s": list(marks), "scored": scored,
            "samples": samples, "samples_per_s": samples / train_s,
            "curve": thin(curve), "evals": evals, "n_envs": n_envs, "hyperparameters": ZOO[task]}


def with_reach(run: dict) -> dict:
    """The run with its reference and when its evaluations first reached it (and half of it)."""
    from agents.logger import first_reaching  # noqa: PLC0415

    target = run["reference"] = REFERENCE.get(run["task"])
    run["first_eval_reaching"] = {} if target is None else {
        name: first_reaching(run["evals"], "eval/return", value) for name, value in (("target", target),
                                                                                   ("half", half(target)))}
    return run


def cpu_name() -> str:
    try:
        with open("/proc/cpuinfo") as f:
            return next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        return "unknown CPU"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--tasks", nargs="+", default=["HalfCheetah-v5", "Hopper-v5", "Walker2d-v5", "Ant-v5",
                                                  "Humanoid-v5"])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--parallel", type=int, default=1, help="runs at once, one core each")
    ap.add_argument("--eval-episodes", type=int, default=10, help="episodes per seed of 3 (default 10)")
    ap.add_argument("--one", nargs=2, metavar=("TASK", "SEED"), help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    unknown = [t for t in args.tasks if t not in ZOO]
    if unknown:
        ap.error(f"--tasks {unknown}: the RL Zoo's hyperparameters are here for {list(ZOO)}")
    if not args.minutes > 0 or args.parallel < 1:
        ap.error(f"--minutes {args.minutes} / --parallel {args.parallel}: both must be positive")
    from warpgym.cli import write_json  # noqa: PLC0415

    os.makedirs(args.out, exist_ok=True)
    scale = args.minutes * 60.0 / MARKS["long"][-1]
    if args.one:
        task, seed = args.one[0], int(args.one[1])
        run = with_reach(train_one(task, seed, args.minutes, tuple(m * scale for m in MARKS["long"]),
                                   args.eval_episodes))
        import stable_baselines3  # noqa: PLC0415

        meta = {"learner": f"stable-baselines3 {stable_baselines3.__version__} PPO, RL Zoo hyperparameters",
                "cpu": cpu_name(), "cores_per_run": 1, "parallel": args.parallel, "scale": scale,
                "date": time.strftime("%Y-%m-%d"), "command": " ".join(["python -m benchmarks.learning.suite_sb3"] + sys.argv[1:])}
        write_json(os.path.join(args.out, f"sb3-{task}-seed{seed}.json"), {"meta": meta, "run": run})
        print(json.dumps({k: run[k] for k in ("task", "seed", "samples", "scored")})[:400], flush=True)
        return 0
    jobs = [(t, s) for t in args.tasks for s in args.seeds]
    cores = sorted(os.sched_getaffinity(0))
    running: list[tuple[subprocess.Popen, int]] = []
    failed = 0
    while jobs or running:
        while jobs and len(running) < args.parallel:
            task, seed = jobs.pop(0)
            busy = {c for _, c in running}
            core = next(c for c in cores if c not in busy) if len(busy) < len(cores) else cores[0]
            cmd = [sys.executable, "-m", "benchmarks.learning.suite_sb3", "--out", args.out,
                   "--minutes", str(args.minutes),
                   "--eval-episodes", str(args.eval_episodes), "--parallel", str(args.parallel),
                   "--one", task, str(seed)]
            log = open(os.path.join(args.out, f"sb3-{task}-seed{seed}.log"), "w")
            env = dict(os.environ, OMP_NUM_THREADS="1", MKL_NUM_THREADS="1")
            proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env,
                                    preexec_fn=lambda core=core: os.sched_setaffinity(0, {core}))
            running.append((proc, core))
        time.sleep(1.0)
        for proc, core in list(running):
            if proc.poll() is not None:
                failed += proc.returncode != 0
                running.remove((proc, core))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
