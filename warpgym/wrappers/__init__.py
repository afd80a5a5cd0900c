"""Adapters that let the learners people already use train warpgym envs, each an optional extra.

=============  ==============================  ===============================  ==================
learner        adapter                         install                          data path
=============  ==============================  ===============================  ==================
rsl_rl         ``rsl_rl.RslRlVecEnv``           ``pip install "warpgym[rsl_rl]"``  torch, env device
skrl           ``skrl.SkrlVecEnv``              ``pip install "warpgym[skrl]"``    torch, env device
rl_games       ``rl_games.RlGamesVecEnv``       ``pip install "warpgym[rl_games]"``  torch, env device
SB3            ``sb3.Sb3VecEnv``                ``pip install "warpgym[sb3]"``     numpy, host (slow)
RLlib          ``rllib.RllibVecEnv``            ``pip install "warpgym[rllib]"``   numpy, host (slow)
Gymnasium      ``numpy_vec.NumpyVecEnv``        (core)                           numpy, host (slow)
=============  ==============================  ===============================  ==================

Each module imports its learner only when it is imported itself, so ``import warpgym`` stays lean.
``common.EpisodeLog`` gives every adapter the same training metrics, whatever the learner logs.
"""
