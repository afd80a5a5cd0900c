"""Warp kernels and ``@wp.func`` helpers of warpgym: stateless, one file per concern."""
