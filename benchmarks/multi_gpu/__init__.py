"""Several GPUs: time to target on 1, 2 and 4 GPUs of a host, the job packing, and RLlib's PPO beside warpgym's."""
