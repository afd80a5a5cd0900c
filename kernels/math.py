"""Small ``@wp.func`` helpers shared by the task kernels."""

import warp as wp


@wp.func
def wrap_angle(a: float):
    # atan2 of sin and cos maps any angle into [-pi, pi]
    return wp.atan2(wp.sin(a), wp.cos(a))


@wp.func
def roll_from_quat(q: wp.quat):
    # xyz Euler roll of an xyzw quaternion, in [-pi, pi]
    sinr = 2.0 * (q[3] * q[0] + q[1] * q[2])
    cosr = q[3] * q[3] - q[0] * q[0] - q[1] * q[1] + q[2] * q[2]
    return wp.atan2(sinr, cosr)


@wp.func
def yaw_from_quat(q: wp.quat):
    # xyz Euler yaw of an xyzw quaternion, in [-pi, pi]
    siny = 2.0 * (q[3] * q[2] + q[0] * q[1])
    cosy = q[3] * q[3] + q[0] * q[0] - q[1] * q[1] - q[2] * q[2]
    return wp.atan2(siny, cosy)


@wp.func
def unscale(x: float, lower: float, upper: float):
    # map [lower, upper] onto [-1, 1]
    return (2.0 * x - upper - lower) / (upper - lower)


@wp.func
def finite_or_zero(x: float):
    if wp.isfinite(x):
        return x
    return 0.0
