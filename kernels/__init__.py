"""Warp kernels and ``@wp.func`` helpers of warpgym, stateless: ``common`` for what both families of tasks
use, ``robots/`` for warpgym's Ant and Humanoid, ``suite/`` for Gymnasium's MuJoCo tasks; the Tensor API's
layout, solver-load tracking and small math beside them."""
