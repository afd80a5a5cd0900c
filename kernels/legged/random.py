"""The purposes of the legged kernels' random streams (``kernels.common.stream``): two kernels of one step never draw
the same numbers for a world."""

RESET = 0
COMMAND = 1
OBSERVATION = 2
INTERVAL = 3  # the interval events (pushes) and their timers
STARTUP = 4  # the randomisation drawn once when the env is built
FINAL_OBSERVATION = 5  # the noise of an ended episode's last observation

TERRAIN = 6  # a world past the top level sent to a random one
