"""Frames and velocities as mjlab reads them from MuJoCo's data: quaternions (w, x, y, z), world velocities of a
body's or site's point from the body's com-based velocity ``cvel``."""

import warp as wp

from kernels.legged.params import LeggedRobot, MjLegged

wp.set_module_options({"enable_backward": False})


@wp.func
def rotate_inverse(q: wp.quat, v: wp.vec3):
    """``v`` (world frame) in the frame of the unit quaternion ``q`` (w, x, y, z)."""
    xyz = wp.vec3(q[1], q[2], q[3])
    t = 2.0 * wp.cross(xyz, v)
    return v - q[0] * t + wp.cross(xyz, t)


@wp.func
def rotate(q: wp.quat, v: wp.vec3):
    """``v`` (frame of ``q``) in the world frame."""
    xyz = wp.vec3(q[1], q[2], q[3])
    t = 2.0 * wp.cross(xyz, v)
    return v + q[0] * t + wp.cross(xyz, t)


@wp.func
def point_velocity(d: MjLegged, w: int, body: int, root: int, point: wp.vec3):
    """World-frame linear velocity of ``point``, fixed to ``body``: MuJoCo's ``cvel`` is taken about the
    tree's centre of mass (``subtree_com`` of its root body)."""
    c = d.cvel[w, body]
    return wp.vec3(c[3], c[4], c[5]) - wp.cross(wp.vec3(c[0], c[1], c[2]), d.subtree_com[w, root] - point)


@wp.func
def angular_velocity(d: MjLegged, w: int, body: int):
    c = d.cvel[w, body]
    return wp.vec3(c[0], c[1], c[2])


@wp.func
def root_velocity_b(d: MjLegged, r: LeggedRobot, w: int):
    """The base's linear and angular velocity in its own frame (mjlab's root_link_lin_vel_b, ang_vel_b)."""
    q = d.xquat[w, r.root_body]
    lin = point_velocity(d, w, r.root_body, r.root_body, d.xpos[w, r.root_body])
    return rotate_inverse(q, lin), rotate_inverse(q, angular_velocity(d, w, r.root_body))


@wp.func
def projected_gravity(q: wp.quat):
    return rotate_inverse(q, wp.vec3(0.0, 0.0, -1.0))


@wp.func
def heading(q: wp.quat):
    """Yaw of the base's forward (x) axis in the world."""
    f = rotate(q, wp.vec3(1.0, 0.0, 0.0))
    return wp.atan2(f[1], f[0])


@wp.func
def sensor3(d: MjLegged, w: int, adr: int):
    return wp.vec3(d.sensordata[w, adr], d.sensordata[w, adr + 1], d.sensordata[w, adr + 2])
