"""One process of a 2-process data-parallel PPO run on the CPU (gloo), started by torchrun from
tests/test_distributed.py. Each process trains on its own point masses; at the end it saves what
must agree across processes."""

import os
import sys

import torch
import torch.distributed as dist

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from agents import Config, OnPolicyRunner  # noqa: E402
from agents.distributed import init_workers  # noqa: E402
from point_mass import PointMassVecEnv  # noqa: E402

init_workers("gloo")
rank = dist.get_rank()
out = sys.argv[1]
env = PointMassVecEnv(32, seed=rank)
cfg = Config(net_dims=(16, 16), horizon_len=10, minibatch_size=160, repeat_times=2, learning_rate=3e-3,
             eval_gap=1e9, save_gap=10**6, seed=0)
runner = OnPolicyRunner(env, cfg, run_dir=os.path.join(out, "run"), print_fn=lambda s: None)
history = runner.learn(max_iterations=int(sys.argv[2]) if len(sys.argv) > 2 else 5)
own = PointMassVecEnv(32, seed=rank)  # this process's first observations, to check the normaliser
first_obs, _ = own.reset()
torch.save({"params": torch.cat([p.detach().flatten() for p in runner.policy.parameters()]),
            "mean": runner.normalizer.mean, "count": runner.normalizer.count, "lr": runner.ppo.lr,
            "history": history, "first_obs": first_obs}, os.path.join(out, f"rank{rank}.pt"))
dist.destroy_process_group()
