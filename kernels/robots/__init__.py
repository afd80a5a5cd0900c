"""The kernels of warpgym's own robots (the Ant and the Humanoid on Newton): actions, observations,
rewards, the step after the physics and the masked reset; their arrays as Warp structs (buffers.py)."""
