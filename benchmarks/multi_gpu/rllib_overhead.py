"""What RLlib's env runner costs per step by itself: its sampling loop around an env that does nothing.

    python -m benchmarks.multi_gpu.rllib_overhead --out OUT.json                     # 1024 and 4096 envs, Ant's sizes
    python -m benchmarks.multi_gpu.rllib_overhead --envs 4096 --obs 108 --actions 21 # the Humanoid's

RLlib's SingleAgentEnvRunner (new API stack) keeps one episode object per env and runs its connectors
and module on numpy batches every step. Here it steps a ``VectorEnv`` whose step returns preallocated
arrays (no physics, no copies), so the runner's rate is an upper bound on any env's samples/s through
it, on this machine's CPU: the runner's loop is single-threaded Python, whatever GPU the env uses. The
same env stepped in a bare loop gives the env's own share. Writes OUT.json with samples/s per size
(median of --repeats timings of --steps steps each).
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import time

import numpy as np



def null_vector_env(num_envs: int, num_obs: int, num_actions: int, episode: int):
    """A next-step-autoreset VectorEnv that returns the same arrays every step and ends each env's episode
    every ``episode`` steps (staggered), as locomotion episodes end."""
    from gymnasium import spaces
    from gymnasium.vector import AutoresetMode, VectorEnv
    from gymnasium.vector.utils import batch_space

    class NullVecEnv(VectorEnv):
        def __init__(self):
            self.num_envs = num_envs
            self.single_observation_space = spaces.Box(-np.inf, np.inf, (num_obs,), np.float32)
            self.single_action_space = spaces.Box(-1.0, 1.0, (num_actions,), np.float32)
            self.observation_space = batch_space(self.single_observation_space, num_envs)
            self.action_space = batch_space(self.single_action_space, num_envs)
            self.metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}
            self.obs = np.zeros((num_envs, num_obs), np.float32)
            self.reward = np.ones(num_envs)
            self.t = np.arange(num_envs) % episode

        def reset(self, *, seed=None, options=None):
            return self.obs.copy(), {}

        def step(self, actions):
            self.t += 1
            done = self.t % episode == 0
            return self.obs.copy(), self.reward, np.zeros(num_envs, bool), done, {}

    return NullVecEnv()


def time_runner(num_envs: int, num_obs: int, num_actions: int, steps: int, repeats: int, episode: int) -> dict:
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.env.single_agent_env_runner import SingleAgentEnvRunner
    from ray.tune.registry import register_env

    name = f"null-{num_envs}-{num_obs}-{num_actions}"
    register_env(name, lambda cfg: null_vector_env(num_envs, num_obs, num_actions, episode))
    config = (PPOConfig().environment(name)
              .env_runners(num_env_runners=0, num_envs_per_env_runner=num_envs, rollout_fragment_length=steps,
                           gym_env_vectorize_mode="vector_entry_point")
              .rl_module(model_config={"fcnet_hiddens": [256, 128, 64], "fcnet_activation": "elu"}))
    runner = SingleAgentEnvRunner(config=config)
    runner.sample(num_timesteps=num_envs * steps)  # warm-up: the module's first call, episode objects
    timings = []
    for _ in range(repeats):
        start = time.perf_counter()
        runner.sample(num_timesteps=num_envs * steps)
        timings.append(time.perf_counter() - start)
    env = null_vector_env(num_envs, num_obs, num_actions, episode)
    actions = np.zeros((num_envs, num_actions), np.float32)
    start = time.perf_counter()
    for _ in range(steps):
        env.step(actions)
    bare = time.perf_counter() - start
    runner.stop()
    median = statistics.median(timings)
    return {"num_envs": num_envs, "num_obs": num_obs, "num_actions": num_actions, "steps": steps,
            "repeats": repeats, "runner_samples_per_s": num_envs * steps / median,
            "runner_ms_per_step": 1e3 * median / steps, "env_alone_ms_per_step": 1e3 * bare / steps}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--envs", type=int, nargs="+", default=[1024, 4096])
    ap.add_argument("--obs", type=int, default=60, help="observation size (Ant 60, Humanoid 108)")
    ap.add_argument("--actions", type=int, default=8, help="action size (Ant 8, Humanoid 21)")
    ap.add_argument("--steps", type=int, default=16, help="steps per timing (one rollout of the Ant's preset)")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--episode", type=int, default=1000, help="episode length in steps")
    ap.add_argument("--out", default=None, help="JSON file to write")
    args = ap.parse_args(argv)
    bad = [f"{flag} {value}" for flag, value in (("--envs", min(args.envs)), ("--steps", args.steps),
                                                 ("--repeats", args.repeats), ("--episode", args.episode)) if value < 1]
    if bad:
        ap.error(f"{', '.join(bad)}: must be positive")
    try:
        import ray
    except ImportError:
        ap.error('RLlib is not installed: pip install "warpgym[rllib]"')
    ray.init(num_cpus=os.cpu_count() or 1, include_dashboard=False, log_to_driver=False, configure_logging=False)
    rows = [time_runner(n, args.obs, args.actions, args.steps, args.repeats, args.episode) for n in args.envs]
    doc = {"cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(), "date": time.strftime("%Y-%m-%d"),
           "rows": rows}
    print("| envs | RLlib's runner: samples/s | ms per step | the env alone: ms per step |\n|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['num_envs']} | {r['runner_samples_per_s'] / 1e3:.1f} k | {r['runner_ms_per_step']:.1f} | "
              f"{r['env_alone_ms_per_step']:.3f} |")
    if args.out:
        from warpgym.cli import write_json

        write_json(args.out, doc)
    return 0


if __name__ == "__main__":
    sys.exit(main())
