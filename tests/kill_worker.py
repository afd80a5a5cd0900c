"""``scripts/train.py`` that kills itself with SIGKILL at one chosen moment, for tests/test_reliability.py.

KILL_AT=PHASE:N picks the moment: halfway through the N-th rollout, the N-th PPO update (after its
second optimiser step), the N-th evaluation (at its tenth step), or the N-th checkpoint write
(half its bytes on disk). Before dying it writes KILL_MARKER: the phase and the last finished
iteration, so the test can tell how much the resumed run may lose."""

import json
import os
import signal
import sys

import torch

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

from agents import runner as runner_module  # noqa: E402

PHASE, N = os.environ["KILL_AT"].split(":")
N = int(N)
calls = {"rollout": 0, "update": 0, "evaluate": 0, "save": 0}
live = {}


def die() -> None:
    with open(os.environ["KILL_MARKER"], "w") as f:
        json.dump({"phase": PHASE, "n": N, "iteration": live["runner"].iteration}, f)
        f.flush()
        os.fsync(f.fileno())
    os.kill(os.getpid(), signal.SIGKILL)


def after_calls(fn, count: int):
    """``fn`` that dies on its ``count``-th call, before running."""
    seen = [0]

    def wrapped(*args, **kwargs):
        seen[0] += 1
        if seen[0] == count:
            die()
        return fn(*args, **kwargs)

    return wrapped


def counted(phase: str, original, arm):
    def wrapped(self, *args, **kwargs):
        live["runner"] = self
        calls[phase] += 1
        if PHASE == phase and calls[phase] == N:
            arm(self)
        return original(self, *args, **kwargs)

    return wrapped


R = runner_module.OnPolicyRunner
R.collect = counted("rollout", R.collect,
                     lambda self: setattr(self.env, "step", after_calls(self.env.step, self.cfg.horizon_len // 2)))
R.update = counted("update", R.update,
                   lambda self: setattr(self.ppo.optimizer, "step", after_calls(self.ppo.optimizer.step, 2)))
R.evaluate = counted("evaluate", R.evaluate,
                     lambda self: setattr(self.eval_env, "step", after_calls(self.eval_env.step, 10)))

original_save = torch.save


def torn_save(obj, f, *args, **kwargs):
    calls["save"] += 1
    if PHASE == "save" and calls["save"] == N:
        import io

        buf = io.BytesIO()
        original_save(obj, buf, *args, **kwargs)
        f.write(buf.getvalue()[: len(buf.getvalue()) // 2])
        f.flush()
        os.fsync(f.fileno())
        die()
    return original_save(obj, f, *args, **kwargs)


torch.save = torn_save

from warpgym.cli import train  # noqa: E402

sys.exit(train.main(sys.argv[1:]))
