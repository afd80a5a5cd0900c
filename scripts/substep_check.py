"""Does a trained Ant policy's gait survive a finer physics step? A gait that only works at the
training step size exploits the integrator, not the robot.

    python scripts/substep_check.py runs/Ant-.../checkpoint.pt --num-envs 256 --steps 300

Runs the deterministic policy for --steps control steps under four settings (2 or 8 substeps per
1/60 s step; 8 or 50 solver and line-search iterations) and prints the forward speed and the torso
height (summed while an env is alive, divided by envs x steps, so a fallen env adds zero), the envs
still alive at the end and the largest joint speed seen.
"""

from __future__ import annotations

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

SETTINGS = [("2 substeps, 8 iterations", 2, 8), ("2 substeps, 50 iterations", 2, 50),
            ("8 substeps, 8 iterations", 8, 8), ("8 substeps, 50 iterations", 8, 50)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint")
    ap.add_argument("--num-envs", type=int, default=256)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--device", default=None)
    args = ap.parse_args(argv)

    import torch  # noqa: PLC0415

    from agents.checkpoint import load, policy_from_checkpoint  # noqa: PLC0415
    from warpgym.device import resolve_device  # noqa: PLC0415
    from warpgym.envs import LocomotionVecEnv  # noqa: PLC0415

    device = resolve_device(args.device)
    ckpt = load(args.checkpoint, torch.device(device))
    cfg = ckpt["config"]
    n = args.num_envs
    for label, substeps, iters in SETTINGS:
        env = LocomotionVecEnv(cfg["env_args"]["task"], num_envs=n, device=device, seed=5, substeps=substeps,
                               sim_options={"solver_iterations": iters, "ls_iterations": iters})
        policy, normalize = policy_from_checkpoint(ckpt, env.num_obs, env.num_actions, torch.device(device))
        obs, _ = env.reset(seed=5)
        alive = torch.ones(n, dtype=torch.bool, device=device)
        vx = torch.zeros(n, device=device)
        z = torch.zeros(n, device=device)
        max_dof_vel = torch.zeros((), device=device)
        with torch.no_grad():
            for _ in range(args.steps):
                obs, _, term, trunc, _ = env.step(policy.act_deterministic(normalize(obs)))
                alive &= ~(term | trunc)
                vx += env.sim.root_vel[:, 0] * alive
                z += env.sim.root_pose[:, 2] * alive
                max_dof_vel = torch.maximum(max_dof_vel, env.sim.dof_vel.abs().max())
        row = {"setting": label, "mean_forward_speed": (vx.sum() / (args.steps * n)).item(),
               "mean_torso_height": (z.sum() / (args.steps * n)).item(), "alive": int(alive.sum()),
               "max_dof_vel": max_dof_vel.item()}
        print(json.dumps(row), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
