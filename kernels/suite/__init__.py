"""The kernels of Gymnasium's MuJoCo suite on MuJoCo Warp: the step after the physics (observation,
reward terms, termination), the masked reset, and the structs and constants they take (params.py)."""
