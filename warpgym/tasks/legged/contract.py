"""What a controller needs around a legged policy (``warpgym export``'s policy.json): the observation's terms in
order, as the task's table lists them, the joints in the action's order with their defaults, scales, gains and
effort limits, the control period and the command's ranges, from MuJoCo's compile of the task's scene."""

from __future__ import annotations

from warpgym.tasks.legged import trained_legged_task
from warpgym.tasks.legged.model import compile_task_scene, policy_terms, resolve


def deployment_contract(name: str, env_args: dict | None = None) -> dict:
    """What a controller needs around a legged policy, from MuJoCo's compile of the task's scene (the robot a run
    trained, from its ``env_args``)."""

    task = trained_legged_task({**(env_args or {}), "task": name})
    compiled, _ = compile_task_scene(task)
    m = compiled.mjm
    idx = resolve(task, m)
    act = idx.joint_actuator
    rounded = lambda values: [round(float(v), 6) for v in values]  # noqa: E731
    return {
        "mirrors": task.mirrors, **({"robot": task.robot.label} if task.robot is not None else {}),
        "control_dt": task.decimation * task.timestep, "physics_dt": task.timestep,
        "observation": [{"name": n, "size": size, "what": what} for n, size, what in policy_terms(task, idx, len(act))],
        "action": {"joints": list(idx.joint_names), "default_joint_pos": rounded(idx.default_joint_pos),
                   "scale": rounded(idx.action_scale), "target": "default_joint_pos + scale * action [rad]",
                   # the scene's position actuators: force = stiffness * (target - q) - damping * qdot, clamped
                   "stiffness": rounded(m.actuator_gainprm[act, 0]), "damping": rounded(-m.actuator_biasprm[act, 2]),
                   "effort_limit": rounded(m.actuator_forcerange[act, 1])},
        # the ranges training drew commands from: at first, then from each stage of the command curriculum on
        "command": {"lin_vel_x": list(task.lin_vel_x), "lin_vel_y": list(task.lin_vel_y),
                    "ang_vel_z": list(task.ang_vel_z),
                    "stages": [{"from_env_step": step, **{k: list(r) for k, r in
                                                          zip(("lin_vel_x", "lin_vel_y", "ang_vel_z"), ranges) if r}}
                               for step, *ranges in task.command_stages]},
    }
