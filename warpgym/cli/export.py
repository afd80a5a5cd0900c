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
    ap.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                    help="a module of your own that registers the run's task (a run of --task MODULE:NAME); a run's "
                         "files never import code themselves")
    ap.add_argument("--out", default=None, help="folder for the files (default: export/ in the run directory)")
    ap.add_argument("--no-onnx", action="store_true", help="write policy.pt2 and policy.json only")
    return ap


def main(argv=None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    import torch  # noqa: PLC0415

    import warpgym  # noqa: PLC0415
    from agents.checkpoint import load_for_command  # noqa: PLC0415
    from agents.export import deployable, write_exported_program, write_onnx  # noqa: PLC0415
    from warpgym.cli import run_task, write_json  # noqa: PLC0415

    path, ckpt = load_for_command(args.checkpoint, torch.device("cpu"))
    name = ckpt["config"]["env_args"]["task"]
    try:
        entry = run_task(name, args.imports)
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
        **(entry.export_contract(name, ckpt["config"]["env_args"]) if entry.export_contract is not None else
           {"observation": f"the observation of warpgym/{name}'s env (docs/tasks.md)",
            "action": f"the action warpgym/{name}'s env takes (docs/tasks.md)"}),
    }
    write_json(os.path.join(out, "policy.json"), contract)
    print(f"wrote {', '.join(os.path.join(out, f) for f in [*files.values(), 'policy.json'])}: {name}, "
          f"{spec['num_obs']} observations in, {spec['num_actions']} actions out")
    return 0


if __name__ == "__main__":
    sys.exit(main())
