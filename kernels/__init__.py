"""Warp kernels and ``@wp.func`` helpers of warpgym, stateless: ``common`` for what every family of tasks
uses, ``robots/`` for warpgym's Ant and Humanoid, ``suite/`` for Gymnasium's MuJoCo tasks, ``legged/`` for
mjlab's velocity tasks (their terms, one function each, and the step they are called from); the Tensor API's
layout, solver-load tracking and small math beside them."""
