"""``scripts/train.py`` in which one process raises inside its N-th PPO update, for
tests/test_distributed.py: FAIL_AT=RANK:N (it fails at its second optimiser step there)."""

import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from agents import runner as runner_module  # noqa: E402

RANK, N = map(int, os.environ["FAIL_AT"].split(":"))
original = runner_module.OnPolicyRunner.update
calls = [0]


def failing_update(self):
    calls[0] += 1
    if self.workers.rank == RANK and calls[0] == N:
        step, steps = self.ppo.optimizer.step, [0]

        def step_then_fail(*args, **kwargs):  # mid-update: after the first optimiser step
            steps[0] += 1
            if steps[0] == 2:
                raise RuntimeError(f"planted failure in worker {RANK}'s update {N}")
            return step(*args, **kwargs)

        self.ppo.optimizer.step = step_then_fail
    return original(self)


runner_module.OnPolicyRunner.update = failing_update

from warpgym.cli import train  # noqa: E402

sys.exit(train.main(sys.argv[1:]))
