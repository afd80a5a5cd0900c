"""Task definitions, one package per family, each task a frozen dataclass holding every number its kernels read:
``robots/`` (warpgym's own Ant and Humanoid), ``suite/`` (Gymnasium's MuJoCo suite, one file per task),
``legged/`` (mjlab's velocity tasks as tables of terms); ``terms.py`` and ``dispatch.py``: a term, a table of
terms and the Warp function a table becomes; ``presets.py``: each task's PPO settings; ``registry.py``: every task
of every family and what the commands need of it."""
