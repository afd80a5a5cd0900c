"""Random streams of the legged kernels: one per purpose, fresh per (seed, step, world) as ``kernels.common.env_rng``
draws them, so that two kernels of one step never draw the same numbers for a world."""

import warp as wp

wp.set_module_options({"enable_backward": False})

RESET = 0
COMMAND = 1
OBSERVATION = 2
PUSH = 3
STARTUP = 4  # the randomisation drawn once when the env is built
FINAL_OBSERVATION = 5  # the noise of an ended episode's last observation


@wp.func
def stream(rng_state: wp.array[wp.int32], w: int, purpose: int):
    step_rng = wp.rand_init(rng_state[0], rng_state[1])
    return wp.rand_init(wp.randi(step_rng) + purpose * 7919, w)
