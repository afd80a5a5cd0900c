"""Write a trained policy for another program to run: the robot's controller, ONNX Runtime, libtorch.

    warpgym export runs/go1                  # into runs/go1/export/
    warpgym export runs/go1 --out go1_policy

Three files: ``policy.onnx`` (input ``obs``, output ``actions``, any batch size; needs ``pip install
"warpgym[export]"``), ``policy.pt2`` (``torch.export``'s program: ``torch.export.load(path).module()``) and
``policy.json``, what a controller needs around them.
Both models take the policy's observation, float32 (batch, num_obs), the normaliser inside, and give the actor's
mean, the action evaluation plays. For the legged tasks ``policy.json`` lists the observation's terms in order,
the joints in the action's order with their default positions, action scales, position gains and effort limits
(the joint target is ``default_joint_pos + scale * action``), the control period and the command's ranges: the
deployment contract of mjlab's velocity tasks. For the other tasks, the observation and action are those of the
task's env (docs/tasks.md).
"""

from __future__ import annotations

import os
import sys

from warpgym.cli.flags import CommandParser


def parser() -> CommandParser:
    ap = CommandParser(prog="warpgym export", description=__doc__)
    ap.add_argument("checkpoint", help="a run directory (its checkpoint.pt) or a checkpoint file")
    ap.add_argument("--out", default=None, help="folder for the files (default: export/ in the run directory)")
    ap.add_argument("--no-onnx", action="store_true", help="write policy.pt2 and policy.json only")
    return ap


def legged_contract(name: str) -> dict:
    """What a controller needs around a legged policy, from MuJoCo's compile of the task's scene."""
    from warpgym.tasks.legged import get_legged_task  # noqa: PLC0415
    from warpgym.tasks.legged.model import compile_task_scene, policy_terms, resolve  # noqa: PLC0415

    task = get_legged_task(name)
    compiled, _ = compile_task_scene(task)
    m = compiled.mjm
    idx = resolve(task, m)
    act = idx.joint_actuator
    rounded = lambda values: [round(float(v), 6) for v in values]  # noqa: E731
    return {
        "mirrors": task.mirrors,
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


def main(argv=None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    import torch  # noqa: PLC0415

    import warpgym  # noqa: PLC0415
    from agents.checkpoint import load_for_command  # noqa: PLC0415
    from agents.export import deployable, write_exported_program, write_onnx  # noqa: PLC0415
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    path, ckpt = load_for_command(args.checkpoint, torch.device("cpu"))
    name = ckpt["config"]["env_args"]["task"]
    try:
        entry = task_entry(name)
    except ValueError as e:
        ap.error(f"{path}: {e}")
    if not args.no_onnx:
        try:
            import onnx  # noqa: F401, PLC0415
        except ImportError:
            ap.error('ONNX needs the onnx package: pip install "warpgym[export]" (or pass --no-onnx for policy.pt2 '
                     "and policy.json alone)")
    out = args.out or os.path.join(os.path.dirname(os.path.abspath(path)), "export")
    os.makedirs(out, exist_ok=True)
    module = deployable(ckpt)
    spec = ckpt["spec"]
    files = {}
    if not args.no_onnx:
        write_onnx(module, spec["num_obs"], os.path.join(out, "policy.onnx"))
        files["onnx"] = "policy.onnx"
    write_exported_program(module, spec["num_obs"], os.path.join(out, "policy.pt2"))
    files["torch_export"] = "policy.pt2"
    contract = {
        "task": name, "num_obs": spec["num_obs"], "num_actions": spec["num_actions"], "files": files,
        "input": "obs: float32 (batch, num_obs), the policy's observation; the normaliser is inside the model",
        "output": "actions: float32 (batch, num_actions), the actor's mean",
        "normalizer": bool(ckpt["config"].get("normalize_obs", False)),
        "trained": {"checkpoint": os.path.abspath(path), "iteration": ckpt.get("iteration"),
                    "samples": ckpt.get("samples")},
        "warpgym": warpgym.__version__,
        **(legged_contract(name) if entry.family == "legged" else
           {"observation": f"the observation of warpgym/{name}'s env (docs/tasks.md)",
            "action": f"the action warpgym/{name}'s env takes (docs/tasks.md)"}),
    }
    write_json(os.path.join(out, "policy.json"), contract)
    print(f"wrote {', '.join(os.path.join(out, f) for f in [*files.values(), 'policy.json'])}: {name}, "
          f"{spec['num_obs']} observations in, {spec['num_actions']} actions out")
    return 0


if __name__ == "__main__":
    sys.exit(main())
