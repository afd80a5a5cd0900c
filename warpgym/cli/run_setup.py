"""What a `warpgym train` run is before it trains: its plan (a new run from the flags, or the run being
resumed, read back from its config.json and agreed on by every process) and its Config, the flags checked
together against the task's preset."""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, fields

from agents import Config
from agents.data_parallel import envs_per_process
from warpgym.cli import train_args
from warpgym.cli.train_args import with_flag_names


def default_envs_and_iterations(kind: str, task: str) -> tuple[int, int]:
    """The task's default envs and iterations on a device kind ("cuda" or "cpu"): its registry entry's."""
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    return task_entry(task).defaults(kind)


def known_task(name) -> bool:
    """A task name the registry has, or a user's (``module:Name``), whose module the resume imports if asked."""
    from warpgym.tasks.registry import REGISTRY  # noqa: PLC0415

    return isinstance(name, str) and (name in REGISTRY or ":" in name)


def check_resume(run_dir: str, saved: dict, task_flag: str | None) -> bool:
    """The run directory's checkpoint, if it has one yet (the return value), is readable and of the
    task its config names, and the task asked for (if any) is that one: checked on the CPU before
    any model is built."""
    from agents.checkpoint import load  # noqa: PLC0415

    import torch  # noqa: PLC0415

    task = saved.get("task")
    if task_flag is not None and task_flag != task:  # the flag is canonical already (train_args.check_values)
        raise SystemExit(f"--task {task_flag} --resume {run_dir}: that run trains {task}; drop --task, or start "
                         f"a new {task_flag} run with --run-dir")
    path = os.path.join(run_dir, "checkpoint.pt")
    if not os.path.exists(path):
        return False  # stopped before its first save: the run starts again from iteration 0
    try:
        ckpt = load(path, torch.device("cpu"))
    except (FileNotFoundError, ValueError) as e:
        raise SystemExit(f"--resume {run_dir}: {e}") from None
    ckpt_task = (ckpt["config"].get("env_args") or {}).get("task")
    if ckpt_task is not None and ckpt_task != task:
        raise SystemExit(f"--resume {run_dir}: its checkpoint.pt was trained on {ckpt_task} but config.json says "
                         f"{task}; the folder mixes two runs: resume from a run directory written by one run")
    return True


def build_config(args, task: str, num_envs: int, device: str, saved: dict | None = None, processes: int = 1):
    """The task's preset for the run's learner (``--algo``), or the saved config of the run being resumed, then the
    flags given; the training env is this process's share of ``num_envs`` among ``processes`` (Config.multi_gpu)."""
    from agents.algos import by_agent  # noqa: PLC0415

    algo = by_agent(saved.get("agent")).name if saved is not None else (getattr(args, "algo", None) or "ppo")
    if algo == "sac":
        cfg = sac_config(args, task, device, saved)
        local_envs = num_envs
    else:
        cfg = ppo_config(args, task, num_envs, device, saved)
        local_envs = envs_per_process(cfg.multi_gpu, num_envs, processes)
    from warpgym.envs import entry_point  # noqa: PLC0415
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    entry = task_entry(task)
    # the learner's env: for Gymnasium's tasks, actions in [-1, 1] mapped onto the control ranges
    common = {"task": task, "device": device, "max_episode_steps": args.episode_length, **dict(entry.learner_kwargs),
              **({"robot": args.robot} if getattr(args, "robot", None) else {})}
    if entry.physics_flags:
        from warpgym.tasks.robots import get_task  # noqa: PLC0415

        # The whole physics goes into the config, not only what the flags changed: a checkpoint then
        # replays (play.py, sim2sim.py) with the physics it was trained with, whatever the defaults later.
        defined = get_task(task)
        common.update(substeps=args.substeps or defined.substeps,
                      physics=defined.physics.replace(**(args.physics or {})).to_dict())
    elif args.substeps or args.physics:
        raise ValueError(f"--substeps / --physics set warpgym's own robots' physics; {task} simulates "
                         "Gymnasium's model file as it is: drop them")
    env_class = entry_point(entry.vector_entry_point)
    return cfg.replace(
        env_class=env_class,
        env_args={**common, "num_envs": local_envs, "seed": args.seed},
        eval_env_class=env_class,
        eval_env_args={**common, "num_envs": cfg.eval_envs, "seed": args.seed + 1},
    )


def from_saved(config, saved: dict, sequences: tuple[str, ...]):
    """A learner's config as a run's config.json holds it (its lists of widths back to tuples; what is not one of the
    config's fields, or is the envs', left out: the command rebuilds those)."""
    known = {f.name for f in fields(config)} - {"env_class", "env_args", "eval_env_class", "eval_env_args"}
    return config(**{k: (tuple(v) if k in sequences else v) for k, v in saved.items() if k in known})


def run_changes(args) -> dict:
    """The flags of the run itself, as config fields (every learner has them)."""
    return {k: v for k, v in {
        "save_gap": args.save_gap, "eval_gap": args.eval_gap, "eval_envs": args.eval_envs,
        "keep_checkpoints": args.keep_checkpoints or None, "save_at": tuple(args.save_at) if args.save_at else None,
        "target": args.target}.items() if v is not None}


def sac_config(args, task: str, device: str, saved: dict | None):
    """The off-policy learner's config: the task's SAC preset or the resumed run's, then --config and the run's flags."""
    from agents.sac import SACConfig  # noqa: PLC0415

    if saved is not None:
        cfg = from_saved(SACConfig, saved, ("actor_dims", "critic_dims"))
    else:
        from warpgym.tasks.registry import task_entry  # noqa: PLC0415

        cfg = SACConfig.from_preset(task_entry(task).sac_preset, seed=args.seed)
    changes = run_changes(args)
    if saved is None and "eval_envs" not in changes and device == "cpu":
        changes["eval_envs"] = 4
    return cfg.replace(**{**(args.config or {}), **changes})


def ppo_config(args, task: str, num_envs: int, device: str, saved: dict | None) -> Config:
    if saved is not None:
        # a run saved before Config.multi_gpu gave each process num_envs envs and mini-batches of minibatch_size;
        # one saved before Config.minibatch_size wrote batch_size (Config.renamed)
        cfg = from_saved(Config, {"multi_gpu": "grow-batch", **Config.renamed(saved)}, ("net_dims",))
    else:
        from warpgym.tasks.registry import task_entry  # noqa: PLC0415

        cfg = Config.from_preset(task_entry(task).preset, seed=args.seed)
    changes = {k: v for k, v in {
        "horizon_len": args.horizon_len, "repeat_times": args.repeat_times, "learning_rate": args.learning_rate,
        "minibatch_size": args.minibatch_size, "overlap": args.overlap or None,
        "compile_update": args.compile_update or None, "multi_gpu": args.multi_gpu,
    }.items() if v is not None}
    changes.update(run_changes(args))
    if saved is None and "eval_envs" not in changes and device == "cpu":
        changes["eval_envs"] = 4
    cfg = cfg.replace(**{**(args.config or {}), **changes})
    samples = num_envs * cfg.horizon_len
    batch = cfg.minibatch_size
    if saved is None and args.minibatch_size is None and "minibatch_size" not in (args.config or {}) and (
            batch > samples // 2 or samples % batch):
        batch = max(samples // 2, 1)  # the preset's mini-batch does not fit this env count
    return cfg.replace(minibatch_size=batch)


def same_on_every_worker(text: str, device: str) -> str:
    import torch  # noqa: PLC0415

    from agents.distributed import Workers  # noqa: PLC0415

    workers = Workers()
    return workers.broadcast_bytes(text.encode() if workers.is_main else None, torch.device(device)).decode()


def read_run_config(run_dir: str, device: str | None) -> dict:
    """The config.json of the run to resume. Only rank 0 needs the file: on several machines the
    others receive its bytes."""
    import torch  # noqa: PLC0415

    from agents.distributed import Workers  # noqa: PLC0415

    workers = Workers()
    data = None
    if workers.is_main:
        path = os.path.join(run_dir, "config.json")
        if not os.path.isfile(path):
            raise SystemExit(f"--resume {run_dir}: no config.json there; pass a run directory written by warpgym train")
        with open(path, "rb") as f:
            data = f.read()
        check_run_config(path, data)
    return json.loads(workers.broadcast_bytes(data, torch.device(device or "cpu")))


RUN_KEYS = ("task", "device", "num_envs", "seed", "env_args")


def check_run_config(path: str, data: bytes) -> None:
    """A resumed run's config.json is whole JSON with the keys train.py writes, or the run stops with
    one line saying which file and what is wrong with it."""
    fix = ("restore it from a copy, or start a new run with --run-dir (the checkpoint alone does not say "
           "how the envs were built)")
    try:
        saved = json.loads(data)
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        what = "empty" if not data.strip() else f"not valid JSON ({e})"
        raise SystemExit(f"--resume: {path} is damaged: {what}; {fix}") from None
    missing = [k for k in RUN_KEYS if not isinstance(saved, dict) or k not in saved]
    if missing or not isinstance(saved.get("env_args"), dict) or not known_task(saved["task"]):
        raise SystemExit(f"--resume: {path} is not a warpgym run's config (missing or wrong: "
                         f"{missing or ['env_args' if not isinstance(saved.get('env_args'), dict) else 'task']}); {fix}")
    from warpgym.tasks.names import recorded  # noqa: PLC0415

    try:
        recorded(saved["task"], flag=f"--task {saved['task']}")
    except ValueError as e:
        raise SystemExit(f"--resume: {e}") from None


@dataclass
class RunPlan:
    """Where a run lives and what it trains: a new run from the flags, or the one being resumed."""

    task: str
    run_dir: str
    device: str
    num_envs: int
    saved: dict | None  # the resumed run's config.json
    has_checkpoint: bool  # the resumed run saved a checkpoint (else it starts again from iteration 0)


def plan_run(args, rank: int) -> RunPlan:
    """The run to train. Resuming, the run's own config.json decides, and the flags it was started with are
    restored into ``args``; every process agrees on the answers rank 0 reads."""
    from warpgym.sim.device import resolve_device  # noqa: PLC0415
    from warpgym.sim.physics import recorded  # noqa: PLC0415

    if args.resume:
        saved = read_run_config(args.resume, args.device)
        device = resolve_device(args.device or saved["device"])
        found = str(int(check_resume(args.resume, saved, args.task))) if rank == 0 else ""
        args.seed = saved["seed"]
        args.episode_length = saved["env_args"].get("max_episode_steps")
        args.robot = saved["env_args"].get("robot")
        args.substeps = saved["env_args"].get("substeps")
        args.physics = recorded(saved["env_args"].get("physics"))
        return RunPlan(saved["task"], args.resume, device, saved["num_envs"], saved,
                       same_on_every_worker(found, device) == "1")
    task = args.task or "Ant"  # canonical (train_args.check_values)
    device = resolve_device(args.device)
    num_envs = args.num_envs or default_envs_and_iterations(device_kind(device), task)[0]
    run_dir = args.run_dir or os.path.join("runs", f"{task}-{time.strftime('%Y%m%d-%H%M%S')}")
    run_dir = same_on_every_worker(run_dir, device)  # a default name could differ by a second
    return RunPlan(task, run_dir, device, num_envs, None, False)


def device_kind(device: str) -> str:
    return "cuda" if device.startswith("cuda") else "cpu"


def configure(args, plan: RunPlan, rank: int, processes: int) -> Config:
    """The run's Config, its flags checked together (a wrong one exits with status 2 and one line); rank r's
    envs draw their own resets; without a budget, the task's default number of iterations."""
    try:
        cfg = build_config(args, plan.task, plan.num_envs, plan.device, plan.saved, processes)
        if cfg.agent == "AgentPPO":
            cfg.check_batch(cfg.env_args["num_envs"], processes)
    except ValueError as e:
        train_args.parser().error(with_flag_names(str(e)))
    if rank > 0:  # rank r's envs draw their own resets (seed + 1000 r); rank 0 alone logs, evaluates and saves
        cfg = cfg.replace(env_args={**cfg.env_args, "seed": cfg.env_args["seed"] + 1000 * rank})
        args.no_eval = True
    if args.max_iterations is None and args.total_steps is None and args.time_limit is None:
        args.max_iterations = default_envs_and_iterations(device_kind(plan.device), plan.task)[1]
    return cfg
