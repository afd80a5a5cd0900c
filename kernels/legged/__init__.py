"""Kernels of the legged robots' velocity tasks (mjlab's definitions): actions, contact bookkeeping per physics
step, rewards and terminations, pushes, resets, commands and observations."""
