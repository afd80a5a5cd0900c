"""A control step's actions into MuJoCo's controls, and what mjlab's contact sensors keep after every physics
step: how long each foot has been in the air or on the ground, and the physics steps with a contact of each group."""

import warp as wp

from kernels.legged.frames import sensor3
from kernels.legged.params import NUM_GROUPS, LeggedParams, LeggedRobot, LeggedState, MjLegged

wp.set_module_options({"enable_backward": False})


@wp.kernel
def apply_legged_actions(
    actions_in: wp.array2d[float],  # (N, J) the policy's actions, one per joint in the model's joint order
    r: LeggedRobot,
    st: LeggedState,
    ctrl: wp.array2d[float],  # (N, J) out: each joint's actuator's position target
    nan_count: wp.array[wp.int32],  # (N,) out: non-finite action entries, applied as 0
):
    """mjlab's JointPositionAction: target = action * scale + default position - encoder bias (the robot aims at
    the position its biased encoder would read)."""
    w = wp.tid()
    bad = int(0)
    for j in range(actions_in.shape[1]):
        x = actions_in[w, j]
        if not wp.isfinite(x):
            x = 0.0
            bad += 1
        st.prev_action[w, j] = st.action[w, j]
        st.action[w, j] = x
        ctrl[w, r.joint_actuator[j]] = x * r.action_scale[j] + r.default_joint_pos[j] - st.encoder_bias[w, j]
    nan_count[w] = bad
    for g in range(NUM_GROUPS):
        st.collision_hits[w, g] = 0


@wp.kernel
def track_feet(p: LeggedParams, r: LeggedRobot, d: MjLegged, st: LeggedState):
    """After each physics step (mjlab's ContactSensor.update): air and contact times of each foot, from the
    contact sensors that step computed, and for each contact group whether any of its sensors felt more than the
    threshold."""
    w = wp.tid()
    for f in range(r.foot_found.shape[0]):
        contact = d.sensordata[w, r.foot_found[f]] > 0.0
        if contact:
            st.air_time[w, f] = 0.0
            st.contact_time[w, f] = st.contact_time[w, f] + p.physics_dt
        else:
            st.air_time[w, f] = st.air_time[w, f] + p.physics_dt
            st.contact_time[w, f] = 0.0
    felt = int(0)  # a bit per group that felt more than the threshold this physics step
    for h in range(r.hit_force.shape[0]):
        if wp.length(sensor3(d, w, r.hit_force[h])) > p.collision_force:
            felt = felt | (1 << r.hit_group[h])
    for g in range(NUM_GROUPS):
        if (felt >> g) & 1 != 0:
            st.collision_hits[w, g] = st.collision_hits[w, g] + 1
