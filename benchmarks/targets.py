"""The speeds the benchmarks time training against, one table for all of them.

The training episodes' mean forward speed [m/s]: the first is "walking" (docs/benchmarks.md's
time-to-walk figures, the fidelity and learner tables, the RLlib comparison), the second a trained
gait (issue 31's envs-per-GPU and overlap runs).
"""

TARGETS = {"Ant": (3.0, 8.0), "Humanoid": (2.0, 6.0)}
WALKING = {task: speeds[0] for task, speeds in TARGETS.items()}
