"""Train a warpgym task with another learner, through warpgym's adapters (warpgym/wrappers).

    warpgym train-with rsl_rl --task Ant --time-limit 120
    warpgym train-with skrl --task Ant --num-envs 4096
    warpgym train-with rl_games --task Humanoid
    warpgym train-with sb3 --task Ant --num-envs 64      # numpy: the slow path
    warpgym train-with rllib --task Ant                   # RLlib's PPO, numpy through the host

Each learner runs with its own published hyperparameters for Isaac Gym's Ant and Humanoid
(rsl_rl: Isaac Lab's; skrl: skrl's IsaacGymEnvs examples; rl_games: IsaacGymEnvs' AntPPO and
HumanoidPPO; SB3: its defaults scaled to the batch; RLlib: rl_games' numbers in RLlib's PPO).
The legged tasks train with rsl_rl only, on mjlab's rl_cfg for them (the actor on the policy's
observation, the critic on its own); the other adapters hand their learners one observation.
Whatever the learner logs itself, the run directory gets warpgym's metrics.jsonl/csv (return, length and forward speed of the training
episodes, samples, wall-clock time) and the two plots, so the learners compare on one figure.
Install the learner with its extra: pip install "warpgym[rsl_rl]" (or skrl, rl_games, sb3, rllib).
"""

from __future__ import annotations

import json
import os
import sys
import time

from warpgym.cli import process_start_time, write_json
from warpgym.cli.flags import CommandParser, check_device, non_negative_int, positive_float, positive_int

PROCESS_START = process_start_time()  # as train.py's: the clock starts with the process

LEARNERS = ("rsl_rl", "skrl", "rl_games", "sb3", "rllib")
PIP_NAME = {"rsl_rl": "rsl_rl", "skrl": "skrl", "rl_games": "rl_games", "sb3": "stable_baselines3", "rllib": "ray.rllib"}
# samples per environment between updates, as each learner's published Ant/Humanoid config has it
HORIZON = {"rsl_rl": {"Ant": 32, "Humanoid": 32}, "skrl": {"Ant": 16, "Humanoid": 32},
           "rl_games": {"Ant": 16, "Humanoid": 32}, "sb3": {"Ant": 64, "Humanoid": 64},
           "rllib": {"Ant": 16, "Humanoid": 32}}
# Gymnasium's suite: the Humanoid's horizon (the SB3 one for sb3) and, for the two humanoids, its wider network
WIDE = {"Humanoid", "Humanoid-v5", "HumanoidStandup-v5"}


def asymmetric(task: str) -> bool:
    """The task's critic has an observation group of its own (the legged tasks'): mjlab's rl_cfg trains them."""
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    return task_entry(task).asymmetric


def horizon_of(learner: str, task: str) -> int:
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    if asymmetric(task):  # mjlab's num_steps_per_env, its preset's
        return task_entry(task).preset["horizon_len"]
    return HORIZON[learner].get(task, HORIZON[learner]["Humanoid"])


def parser() -> CommandParser:
    ap = CommandParser(prog="warpgym train-with", description=__doc__)
    ap.add_argument("learner", help=f"one of {', '.join(LEARNERS)}")
    ap.add_argument("--task", default="Ant", help="Ant, Humanoid, one of Gymnasium's suite (Hopper-v5, ...) or, with "
                    "rsl_rl, a legged task (Go1VelocityFlat-v0, ...)")
    ap.add_argument("--num-envs", type=positive_int(4096), default=None, help="default: 4096 on a GPU, 64 on the CPU")
    ap.add_argument("--device", default=None, help="default: cuda:0 when present, else cpu")
    ap.add_argument("--seed", type=non_negative_int(0), default=0)
    ap.add_argument("--iterations", type=positive_int(500), default=None,
                    help="learner updates (default: 20 on the CPU, 500 on a GPU)")
    ap.add_argument("--time-limit", type=positive_float(300), default=None,
                    help="stop after this many seconds since start")
    ap.add_argument("--episode-length", type=positive_int(1000), default=None,
                    help="steps per episode (task default: 1000)")
    ap.add_argument("--run-dir", default=None, help="default: runs/<Task>-<learner>-<date>-<time>")
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--no-compile", action="store_true", help="rl_games: no torch.compile of its model (its default)")
    ap.add_argument("--gpus", type=positive_int(1), default=1,
                    help="rllib: env runners and learners, one of each per GPU (on the CPU: that many processes)")
    ap.add_argument("--env-runners", type=non_negative_int(8), default=None,
                    help="rllib: env runner processes, each stepping --num-envs robots (default: one per GPU past one, "
                         "else one in this process)")
    for flag, kind, what in (("--horizon-len", positive_int(16), "steps per env between updates"),
                             ("--batch-size", positive_int(32768), "samples per minibatch"),
                             ("--repeat-times", positive_int(4), "epochs per update"),
                             ("--learning-rate", positive_float(3e-4), "Adam's step size")):
        ap.add_argument(flag, type=kind, default=None, help=f"rllib: {what} (default: the task's rl_games numbers)")
    return ap


def parse_args(argv=None):
    ap = parser()
    args = ap.parse_args(argv)
    check_device(ap, args.device)
    if args.learner not in LEARNERS:
        ap.error(f"learner {args.learner!r}: choose one of {', '.join(LEARNERS)}")
    from warpgym.tasks.registry import task_names  # noqa: PLC0415

    names = {name.lower(): name for name in task_names()}
    if args.task.lower() not in names:
        ap.error(f"--task {args.task!r}: choose one of {list(names.values())}")
    args.task = names[args.task.lower()]
    if asymmetric(args.task) and args.learner != "rsl_rl":
        ap.error(f"--task {args.task}: of the adapters' learners only rsl_rl trains the legged tasks (its observation "
                 f"groups give the critic its own observation): `warpgym train-with rsl_rl --task {args.task}`, or "
                 f"`warpgym train --task {args.task}`")
    rllib_only = [f for f in ("horizon_len", "batch_size", "repeat_times", "learning_rate") if getattr(args, f) is not None]
    rllib_only += [f for f, default in (("gpus", 1), ("env_runners", None)) if getattr(args, f) != default]
    if rllib_only and args.learner != "rllib":
        ap.error(f"--{rllib_only[0].replace('_', '-')} is an rllib setting: the other learners run their published numbers")
    if args.gpus > 1 and args.env_runners not in (None, 0, args.gpus):
        # Ray packs fractional GPUs onto one: only a runner per GPU keeps the DDP learners apart (rllib_run.gpu_shares)
        ap.error(f"--env-runners {args.env_runners} with --gpus {args.gpus}: on several GPUs each GPU takes one env "
                 f"runner beside its learner; leave --env-runners out (or give {args.gpus}), or spread runners on one GPU")
    if args.env_runners is None:
        args.env_runners = args.gpus if args.gpus > 1 else 0
    try:
        __import__(PIP_NAME[args.learner])
    except ImportError:
        ap.error(f"{args.learner} is not installed: pip install \"warpgym[{args.learner}]\"")
    return args


# ---------------------------------------------------------------- one function per learner
def rsl_rl_cfg(task: str, horizon: int) -> dict:
    """Isaac Lab's rsl_rl settings for the Ant and the Humanoid (a smaller step for the humanoids), or, for a legged
    task, mjlab 1.6's rl_cfg of its velocity tasks (the Go1's and the G1's are the same: a larger network, an entropy
    bonus, the critic on the task's own critic observation group)."""
    legged = asymmetric(task)
    net = {"class_name": "MLPModel", "hidden_dims": [512, 256, 128] if legged else [400, 200, 100],
           "activation": "elu", "obs_normalization": True}
    distribution = {"class_name": "GaussianDistribution", "init_std": 1.0, **({"std_type": "scalar"} if legged else {})}
    return {
        "num_steps_per_env": horizon, "save_interval": 10**9,
        "obs_groups": {"actor": ["policy"], "critic": ["critic" if legged else "policy"]},
        "check_for_nan": False,  # a host read per step; warpgym counts NaNs on the device (env.fault_counters)
        "logger": "tensorboard", "multi_gpu": None,
        "actor": {**net, "distribution_cfg": distribution},
        "critic": dict(net),
        "algorithm": {"class_name": "PPO", "value_loss_coef": 1.0, "use_clipped_value_loss": True, "clip_param": 0.2,
                      "entropy_coef": 0.01 if legged else 0.0, "num_learning_epochs": 5, "num_mini_batches": 4,
                      "learning_rate": 1e-3 if legged else 3e-4 if task in WIDE else 5e-4, "schedule": "adaptive",
                      "gamma": 0.99, "lam": 0.95, "desired_kl": 0.01, "max_grad_norm": 1.0},
    }


def run_rsl_rl(env, args, horizon: int, run_dir: str) -> None:
    from rsl_rl.runners import OnPolicyRunner  # noqa: PLC0415

    runner = OnPolicyRunner(env, rsl_rl_cfg(args.task, horizon), log_dir=os.path.join(run_dir, "rsl_rl"), device=str(env.device))
    try:
        runner.learn(args.iterations)
    finally:
        args.learner_object = runner


def run_skrl(env, args, horizon: int, run_dir: str) -> None:
    import torch  # noqa: PLC0415
    from skrl.agents.torch.ppo import PPO, PPO_CFG  # noqa: PLC0415
    from skrl.memories.torch import RandomMemory  # noqa: PLC0415
    from skrl.models.torch import DeterministicMixin, GaussianMixin, Model  # noqa: PLC0415
    from skrl.resources.preprocessors.torch import RunningStandardScaler  # noqa: PLC0415
    from skrl.resources.schedulers.torch import KLAdaptiveLR  # noqa: PLC0415
    from skrl.trainers.torch import SequentialTrainer  # noqa: PLC0415

    hidden = [400, 200, 100] if args.task in WIDE else [256, 128, 64]

    def mlp(n_in: int, n_out: int) -> torch.nn.Sequential:
        layers, width = [], n_in
        for h in hidden:
            layers += [torch.nn.Linear(width, h), torch.nn.ELU()]
            width = h
        return torch.nn.Sequential(*layers, torch.nn.Linear(width, n_out))

    class Policy(GaussianMixin, Model):
        def __init__(self, observation_space, action_space, device):
            Model.__init__(self, observation_space=observation_space, action_space=action_space, device=device)
            GaussianMixin.__init__(self, clip_actions=False, clip_log_std=True, min_log_std=-20.0, max_log_std=2.0)
            self.net = mlp(self.num_observations, self.num_actions)
            self.log_std = torch.nn.Parameter(torch.zeros(self.num_actions))

        def compute(self, inputs, role=""):
            return self.net(inputs["observations"]), {"log_std": self.log_std}

    class Value(DeterministicMixin, Model):
        def __init__(self, observation_space, action_space, device):
            Model.__init__(self, observation_space=observation_space, action_space=action_space, device=device)
            DeterministicMixin.__init__(self, clip_actions=False)
            self.net = mlp(self.num_observations, 1)

        def compute(self, inputs, role=""):
            return self.net(inputs["observations"]), {}

    dev = env.device
    models = {"policy": Policy(env.observation_space, env.action_space, dev),
              "value": Value(env.observation_space, env.action_space, dev)}
    memory = RandomMemory(memory_size=horizon, num_envs=env.num_envs, device=dev)
    ant = args.task == "Ant"
    cfg = PPO_CFG(rollouts=horizon, learning_epochs=4 if ant else 5, mini_batches=2 if ant else 4,
                  discount_factor=0.99, gae_lambda=0.95, learning_rate=3e-4 if ant else 5e-4,
                  learning_rate_scheduler=KLAdaptiveLR, learning_rate_scheduler_kwargs={"kl_threshold": 0.008},
                  observation_preprocessor=RunningStandardScaler,
                  observation_preprocessor_kwargs={"size": env.observation_space, "device": dev},
                  value_preprocessor=RunningStandardScaler, value_preprocessor_kwargs={"size": 1, "device": dev},
                  grad_norm_clip=1.0, ratio_clip=0.2, value_clip=0.2, entropy_loss_scale=0.0, value_loss_scale=1.0,
                  time_limit_bootstrap=True, rewards_shaper=lambda r, *a, **k: r * 0.01,
                  experiment={"directory": run_dir, "experiment_name": "skrl", "checkpoint_interval": 0,
                              "write_interval": 10 * horizon})  # TensorBoard every 10 updates
    agent = PPO(models=models, memory=memory, observation_space=env.observation_space,
                action_space=env.action_space, device=dev, cfg=cfg)
    trainer = SequentialTrainer(env=env, agents=agent, cfg={"timesteps": args.iterations * horizon,
                                                           "disable_progressbar": True,
                                                           "close_environment_at_exit": False})
    args.learner_object = agent
    trainer.train()


def rl_games_config(task: str, num_envs: int, device: str, iterations: int, horizon: int, run_dir: str,
                    torch_compile: bool = True) -> dict:
    """IsaacGymEnvs' published AntPPO / HumanoidPPO settings, for warpgym's env."""
    humanoid = task == "Humanoid"
    batch = num_envs * horizon
    return {"params": {
        "seed": 0, "algo": {"name": "a2c_continuous"}, "model": {"name": "continuous_a2c_logstd"},
        "network": {"name": "actor_critic", "separate": False,
                    "space": {"continuous": {"mu_activation": "None", "sigma_activation": "None",
                                             "mu_init": {"name": "default"},
                                             "sigma_init": {"name": "const_initializer", "val": 0},
                                             "fixed_sigma": True}},
                    "mlp": {"units": [400, 200, 100] if humanoid else [256, 128, 64], "activation": "elu",
                            "d2rl": False, "initializer": {"name": "default"}, "regularizer": {"name": "None"}}},
        "config": {
            "name": f"warpgym_{task}", "full_experiment_name": "rl_games", "train_dir": run_dir,
            "env_name": "warpgym", "device": device, "ppo": True, "multi_gpu": False, "mixed_precision": False,
            "normalize_input": True, "normalize_value": True, "value_bootstrap": True, "num_actors": num_envs,
            "reward_shaper": {"scale_value": 0.01}, "normalize_advantage": True, "gamma": 0.99, "tau": 0.95,
            "learning_rate": 5e-4 if humanoid else 3e-4, "lr_schedule": "adaptive", "schedule_type": "legacy",
            "kl_threshold": 0.008, "score_to_win": 10**9, "max_epochs": iterations, "save_best_after": 10**9,
            "save_frequency": 0, "grad_norm": 1.0, "entropy_coef": 0.0, "truncate_grads": True, "e_clip": 0.2,
            "horizon_length": horizon, "minibatch_size": min(32768, batch), "mini_epochs": 5 if humanoid else 4,
            "critic_coef": 4 if humanoid else 2, "clip_value": True, "seq_length": 4, "bounds_loss_coef": 0.0001,
            "print_stats": False, "torch_compile": torch_compile, "games_to_track": 100,
        }}}


def run_rl_games(env, args, horizon: int, run_dir: str) -> None:
    from rl_games.common.algo_observer import DefaultAlgoObserver  # noqa: PLC0415
    from rl_games.torch_runner import Runner  # noqa: PLC0415

    from warpgym.wrappers.common import base_env  # noqa: PLC0415
    from warpgym.wrappers.rl_games import register_rl_games  # noqa: PLC0415

    class KeepAgent(DefaultAlgoObserver):  # the Runner builds the agent inside run(): keep a handle on it
        def after_init(self, algo):
            super().after_init(algo)
            args.learner_object = algo

    register_rl_games(lambda: env)
    runner = Runner(algo_observer=KeepAgent())
    base = base_env(env)
    runner.load(rl_games_config(args.task, base.num_envs, str(base.device), args.iterations, horizon, run_dir,
                                torch_compile=not args.no_compile))
    runner.run({"train": True, "play": False})


def run_sb3(env, args, horizon: int, run_dir: str) -> None:
    from stable_baselines3 import PPO  # noqa: PLC0415
    from stable_baselines3.common.vec_env import VecMonitor  # noqa: PLC0415

    from warpgym.wrappers.common import base_env  # noqa: PLC0415

    batch = env.num_envs * horizon
    # SB3 counts episodes itself (VecMonitor), from the rewards and dones it is handed
    model = PPO("MlpPolicy", VecMonitor(env), n_steps=horizon, batch_size=min(batch, max(64, batch // 4)), n_epochs=5,
                learning_rate=3e-4, gamma=0.99, gae_lambda=0.95, seed=args.seed, device=str(base_env(env).device),
                policy_kwargs={"net_arch": [256, 128, 64]}, verbose=0)
    args.learner_object = model
    model.learn(total_timesteps=args.iterations * batch)


# ---------------------------------------------------------------- common frame
def adapter(learner: str, env, log):
    if learner == "rsl_rl":
        from warpgym.wrappers.rsl_rl import RslRlVecEnv as Adapter  # noqa: PLC0415
    elif learner == "skrl":
        from warpgym.wrappers.skrl import SkrlVecEnv as Adapter  # noqa: PLC0415
    elif learner == "rl_games":
        from warpgym.wrappers.rl_games import RlGamesVecEnv as Adapter  # noqa: PLC0415
    elif learner == "rllib":
        from warpgym.wrappers.rllib import RllibVecEnv as Adapter  # noqa: PLC0415
    else:
        from warpgym.wrappers.sb3 import Sb3VecEnv as Adapter  # noqa: PLC0415
    return Adapter(env, log=log)


def main(argv=None, args=None) -> int:
    """Train; ``args`` (from ``parse_args``) gets ``learner_object``, the learner's runner or agent."""
    args = args or parse_args(argv)
    import torch  # noqa: PLC0415

    import warpgym  # noqa: PLC0415,F401
    from agents.logger import MetricsLogger  # noqa: PLC0415
    from warpgym.sim.device import resolve_device  # noqa: PLC0415
    from warpgym.envs import make_vec_env  # noqa: PLC0415
    from warpgym.wrappers.common import EpisodeLog, TimeLimitReached  # noqa: PLC0415

    device = resolve_device(args.device)
    gpu = device.startswith("cuda")
    num_envs = args.num_envs or (4096 if gpu else 64)
    args.iterations = args.iterations or (500 if gpu else 20)
    horizon = getattr(args, "horizon_len", None) or horizon_of(args.learner, args.task)
    runners = max(getattr(args, "env_runners", 0), 1)  # rllib: every runner's rollout, split over the learners
    rollout = runners * num_envs * horizon // max(getattr(args, "gpus", 1), 1)
    if getattr(args, "batch_size", None) and args.batch_size > rollout:
        parser().error(f"--batch-size {args.batch_size} exceeds the {rollout} samples of one rollout per learner "
                       f"({runners} runner(s) x {num_envs} envs x horizon {horizon}): lower --batch-size or raise --num-envs")
    run_dir = args.run_dir or os.path.join("runs", f"{args.task}-{args.learner}-{time.strftime('%Y%m%d-%H%M%S')}")
    os.makedirs(run_dir, exist_ok=True)
    torch.manual_seed(args.seed)
    print(f"warpgym + {args.learner} | {args.task} | {num_envs} envs on {device} | run dir {run_dir}", flush=True)
    logger = MetricsLogger(run_dir)
    rows: list[dict] = []

    def sink(row: dict) -> None:
        row = {"iteration": len(rows) + 1, "samples_per_s": horizon * num_envs / max(row["steps_s"], 1e-9), **row}
        rows.append(row)
        logger.log(row)
        if len(rows) % 10 == 0:
            print(f"it {len(rows):5d} | {row['samples'] / 1e6:7.2f}M samples | {row['samples_per_s'] / 1e3:7.1f}k/s | "
                  f"return {row.get('return', float('nan')):8.1f} | speed {row.get('speed', float('nan')):5.2f} m/s | "
                  f"{row['time_s']:6.1f} s", flush=True)

    stopped = "iterations"
    if args.learner == "rllib" and args.env_runners:  # env runners in their own processes build their own envs
        from warpgym.cli.rllib_run import run_rllib_remote  # noqa: PLC0415

        stopped = run_rllib_remote(args, horizon, num_envs, device, run_dir, sink, PROCESS_START)
    else:
        env = make_vec_env(args.task, num_envs=num_envs, device=device, seed=args.seed,
                           max_episode_steps=args.episode_length)
        log = args.episode_log = EpisodeLog(env, every=horizon, sink=sink, stop_after_s=args.time_limit,
                                            start=PROCESS_START, keep_returns=getattr(args, "keep_returns", False))
        if args.learner == "rllib":
            from warpgym.cli.rllib_run import run_rllib as run  # noqa: PLC0415
        else:
            run = {"rsl_rl": run_rsl_rl, "skrl": run_skrl, "rl_games": run_rl_games, "sb3": run_sb3}[args.learner]
        try:
            run(adapter(args.learner, env, log), args, horizon, run_dir)
        except TimeLimitReached:
            stopped = "time limit"
    logger.close()
    summary = summarize(rows, args, device, num_envs, stopped)
    write_json(os.path.join(run_dir, "summary.json"), summary)
    if not args.no_plots and rows:
        try:
            from agents.plotting import plot_runs  # noqa: PLC0415

            plot_runs([run_dir], run_dir, labels=[f"{args.learner} {num_envs} envs"], title=f"warpgym {args.task}")
        except ImportError:
            print("matplotlib is not installed: pip install 'warpgym[train]' for the plots", flush=True)
    print(json.dumps(summary), flush=True)
    return 0


def summarize(rows: list[dict], args, device: str, num_envs: int, stopped: str) -> dict:
    """Steady throughput and when the training episodes first averaged 1, 2 and 3 m/s (tasks that walk forward)."""
    from agents.logger import first_reaching, steady_median  # noqa: PLC0415

    done = [r for r in rows if "return" in r]
    out = {"learner": args.learner, "task": args.task, "device": device, "num_envs": num_envs, "stopped_by": stopped,
           "iterations": len(rows), "samples": rows[-1]["samples"] if rows else 0,
           "time_s": rows[-1]["time_s"] if rows else 0.0, "samples_per_s": steady_median(rows),
           "final_return": done[-1]["return"] if done else None, "final_speed": done[-1].get("speed") if done else None}
    for v in (1, 2, 3):
        out[f"first_speed_{v}ms"] = first_reaching(rows, "speed", v)
    return out


if __name__ == "__main__":
    sys.exit(main())
