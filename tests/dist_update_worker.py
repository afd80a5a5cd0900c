"""One process of a multi-GPU check, started by torchrun from tests/test_cuda.py: the PPO update
with its mini-batch step captured as a CUDA graph (gradient and KL all-reduce inside the graph)
gives what the eager update gives, on every rank, and the ranks end with one policy.

Each rank fills the rollout buffers with its own data, as it would after collecting from its own
envs; the results go to OUT/rank<r>.pt."""

import copy
import os
import sys

import torch
import torch.distributed as dist

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from agents import Config  # noqa: E402
from agents.actor_critic import ActorCritic  # noqa: E402
from agents.distributed import Workers, init_workers  # noqa: E402
from agents.ppo import PPO  # noqa: E402
from agents.storage import RolloutStorage  # noqa: E402


def fill(storage: RolloutStorage, seed: int, device) -> None:
    g = torch.Generator(device=device).manual_seed(seed)
    for t in (storage.obs, storage.actions, storage.means, storage.values, storage.returns, storage.advantages):
        t.copy_(torch.randn(t.shape, generator=g, device=device))
    storage.log_probs.copy_(-torch.rand(storage.log_probs.shape, generator=g, device=device) * 3)


def main() -> None:
    local = int(os.environ["LOCAL_RANK"])
    torch.cuda.set_device(local)
    device = torch.device(f"cuda:{local}")
    init_workers("nccl", device)
    rank = dist.get_rank()
    cfg = Config(net_dims=(64, 64), horizon_len=8, minibatch_size=1024, repeat_times=3).validated()
    torch.manual_seed(0)
    base = ActorCritic(24, 6, cfg.net_dims).to(device)  # the same weights on every rank
    results = {}
    for graph in (False, True):
        policy = copy.deepcopy(base)
        ppo = PPO(policy, cfg, device, cuda_graph=graph, workers=Workers())
        storage = RolloutStorage(cfg.horizon_len, 512, 24, 6, device)
        for it in range(3):  # captured during the first update, replayed in the next two
            fill(storage, seed=1000 * rank + it, device=device)
            torch.manual_seed(100 + it)  # the same mini-batch shuffles in both modes
            stats = ppo.update(storage, policy.log_std.detach().clone(), num_minibatches=4)
        torch.cuda.synchronize()
        results["graph" if graph else "eager"] = {
            "params": torch.cat([p.detach().flatten() for p in policy.parameters()]).cpu(),
            "stats": {k: v.detach().cpu() for k, v in stats.items()},
            "captured": ppo._graph is not None,
        }
        ppo.release_graph()  # before destroy_process_group, which waits for graphs holding NCCL work
    torch.save(results, os.path.join(sys.argv[1], f"rank{rank}.pt"))
    dist.destroy_process_group()


if __name__ == "__main__":
    main()
