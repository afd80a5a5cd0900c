"""PPO's starting point for each task (``agents.Config`` fields), kept beside the tasks: each registry entry
(``warpgym.tasks.registry``) carries its task's, and a task a user registers carries the preset of the task it
changes (a legged one, the legged tasks'). Why each setting,
and what it scored: docs/benchmarks.md, "Presets"."""

from __future__ import annotations

from typing import Any

from warpgym.tasks.legged import LEGGED as LEGGED_TASKS

# warpgym's Ant and Humanoid: Isaac Gym's rl_games settings, adapted to PPO.
PRESETS: dict[str, dict[str, Any]] = {
    "Ant": dict(net_dims=(256, 128, 64), horizon_len=16, minibatch_size=32768, repeat_times=4,
                learning_rate=3e-4, reward_scale=0.01),
    "Humanoid": dict(net_dims=(400, 200, 100), horizon_len=32, minibatch_size=32768, repeat_times=5,
                     learning_rate=5e-4, reward_scale=0.01, value_coef=2.0),
}
# Gymnasium's MuJoCo suite (v5): why each setting, and what it scored: docs/benchmarks.md, "Presets"
# On several GPUs each steps the preset's envs for 32 / G of the steps (split-horizon: agents/data_parallel.py)
_SUITE = dict(net_dims=(256, 128, 64), horizon_len=32, minibatch_size=32768, repeat_times=5, learning_rate=3e-4,
              reward_scale=0.1, eval_gap=60.0, multi_gpu="split-horizon")
PRESETS.update({
    # no observation normaliser: the cart's position is an input whose running mean follows the cart ("Presets")
    "InvertedPendulum-v5": dict(_SUITE, net_dims=(64, 64), horizon_len=32, minibatch_size=4096, anneal_lr=True,
                                normalize_obs=False),
    "InvertedDoublePendulum-v5": dict(_SUITE, reward_scale=0.01),
    "Reacher-v5": dict(_SUITE, reward_scale=1.0),
    "Pusher-v5": dict(_SUITE, reward_scale=1.0),
    # an entropy bonus: at 0.999 without it two seeds of four let the noise collapse and stalled; its std held at
    # or under 1: with the bonus alone one seed's noise grew to 3.7 and its return fell back under the figure
    # ("Presets")
    "Swimmer-v5": dict(_SUITE, reward_scale=1.0, gamma=0.999, entropy_coef=0.01, max_noise_std=1.0),
    # a larger network: the preset's noise collapsed and its return levelled at 0.91 of the figure ("Presets")
    "HalfCheetah-v5": dict(_SUITE, net_dims=(512, 256, 128)),
    # annealed: under the KL-adapted rate the noise collapsed and the return fell back; 0.999: at 0.99 seeds
    # traded staying up for speed ("Presets")
    "Hopper-v5": dict(_SUITE, anneal_lr=True, gamma=0.999),
    # HalfCheetah's network: paired on one host, both its seeds' policies kept at 3 minutes scored the figure in
    # Gymnasium's env, one of the 256-128-64 preset's two did ("Presets")
    "Walker2d-v5": dict(_SUITE, net_dims=(512, 256, 128)),
    "Ant-v5": _SUITE,
    "Humanoid-v5": dict(_SUITE, net_dims=(400, 200, 100), reward_scale=0.05),
    "HumanoidStandup-v5": dict(_SUITE, net_dims=(400, 200, 100), reward_scale=0.001),
})

# The legged velocity tasks: mjlab's rsl_rl settings (its rl_cfg.py for the Go1 and the G1: 512-256-128 ELU actor
# and critic, both observations normalised, 24 steps a rollout, 5 epochs of 4 mini-batches, an adaptive learning
# rate from 1e-3 under a KL target of 0.01, an entropy bonus of 0.01, no action bound) and rsl_rl's staggered start;
# its rough tasks train with the same settings
LEGGED = dict(net_dims=(512, 256, 128), horizon_len=24, minibatch_size=24576, repeat_times=5, learning_rate=1e-3,
              desired_kl=0.01, entropy_coef=0.01, gamma=0.99, lambda_gae=0.95, clip_ratio=0.2, value_clip=0.2,
              value_coef=1.0, max_grad_norm=1.0, bounds_coef=0.0, reward_scale=1.0, stagger_episodes=True,
              eval_gap=60.0)
PRESETS.update({name: LEGGED for name in LEGGED_TASKS})

# The off-policy learner's starting points (agents.sac.SACConfig fields), by family: `warpgym train --algo sac`.
# The legged tasks take FastSAC's humanoid settings (SACConfig's defaults: batch 8192, 8 critic steps an env step,
# the actor every 4th, gamma 0.97, a 101-atom critic, layer norm, bf16), the critic's support halved: mjlab's rewards
# are scaled by the control step. Gymnasium's tasks and warpgym's robots take SAC's usual gamma and target entropy
# of -1 per action, their rewards scaled so that the suite's returns fit the support. None of these is tuned yet
# (docs/benchmarks.md, "Off-policy learning").
SAC_LEGGED = dict(v_min=-10.0, v_max=10.0, gamma=0.97, eval_gap=60.0)
SAC_SUITE = dict(v_min=-50.0, v_max=150.0, gamma=0.99, reward_scale=0.1, target_entropy_ratio=1.0, alpha_init=0.01,
                 num_updates=4, policy_frequency=2, eval_gap=60.0)
SAC_ROBOTS = dict(v_min=-50.0, v_max=150.0, gamma=0.99, reward_scale=0.01, target_entropy_ratio=1.0, alpha_init=0.01,
                  num_updates=4, policy_frequency=2)
