"""The ElegantRL tutorial's flow: ElegantRL 0.3.6's own ``AgentPPO`` and ``train_agent`` train warpgym's
``IsaacVecEnv`` on the CPU, given ``env_args`` with ``num_envs`` (the key 0.3.6 reads; older releases
read ``env_num``, which warpgym's adapter takes). ``pip install elegantrl==0.3.6`` does not install on
Python 3.11 (its ``gym`` dependency pins box2d-py 2.3.5 and pygame 2.1.0, which have no wheels there
and fail to build); ``pip install --no-deps elegantrl==0.3.6`` installs it, and training needs neither.
CI installs it so; without it this test is skipped."""

import os

import numpy as np
import pytest

import torch

elegantrl = pytest.importorskip("elegantrl")


@pytest.fixture(autouse=True)
def torch_global_state():
    """ElegantRL's train_agent switches autograd off for the whole process (torch.set_grad_enabled(False))
    and sets torch's thread count; the tests after this one need both back."""
    grad, dtype, threads = torch.is_grad_enabled(), torch.get_default_dtype(), torch.get_num_threads()
    yield
    torch.set_grad_enabled(grad)
    torch.set_default_dtype(dtype)
    torch.set_num_threads(threads)


def test_elegantrl_0_3_6_trains_warpgym_for_a_few_hundred_steps(tmp_path):
    from importlib.metadata import version

    from elegantrl.agents import AgentPPO
    from elegantrl.train.config import Config
    from elegantrl.train.run import train_agent

    from warpgym.envs.elegantrl import IsaacVecEnv

    assert version("elegantrl") == "0.3.6", "this test documents ElegantRL 0.3.6"
    env_args = {"env_name": "Ant", "env_num": 4, "num_envs": 4, "max_step": 50, "state_dim": 60, "action_dim": 8,
                "if_discrete": False, "target_return": 1e9, "device_id": -1}
    args = Config(AgentPPO, IsaacVecEnv, env_args)
    args.cwd, args.if_remove, args.gpu_id = str(tmp_path), False, -1
    args.net_dims, args.horizon_len, args.batch_size, args.break_step = (32, 32), 32, 64, 300
    args.eval_times, args.eval_per_step = 1, 100
    train_agent(args)
    assert os.path.exists(tmp_path / "act.pth")
    record = np.load(tmp_path / "recorder.npy")  # one row per evaluation: samples, mean return, ...
    assert record[-1, 0] >= 288  # samples trained on: horizon 32 x 4 envs per update, past the 300-step budget
    assert np.isfinite(record[:, 1]).all()  # the mean evaluation return
