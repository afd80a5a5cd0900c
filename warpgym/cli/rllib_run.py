"""RLlib's PPO on warpgym, for ``warpgym train-with rllib`` (and benchmarks/learning/learners.py).

One GPU: one env runner in this process (``num_env_runners=0``) steps the adapter built here, and one
learner on the same GPU; warpgym's ``EpisodeLog`` reads the episodes as for the other learners.

Several GPUs (``--gpus G``): G env runners and G learners, each a Ray actor, runner i and learner i on GPU i
(``gpu_shares``). ``--env-runners R`` sets the runners apart from the GPUs (on one GPU
too): R runner actors share half of the G GPUs, as RLlib users spread sampling over CPU cores, since each
runner's loop over its episodes runs on one core (benchmarks/multi_gpu/rllib_overhead.py). Every runner steps its
own ``--num-envs`` robots in one warpgym vector env; the learners train one policy with torch DDP,
all-reducing gradients every minibatch. That is RLlib's successor of DD-PPO (its old stack's decentralised PPO, where each worker sampled,
computed gradients and all-reduced them itself): sampling and learning are now separate actors, and
the runners receive the new weights after every update. The episodes are then read from RLlib's own
metrics, with warpgym's forward speed added by ``ForwardSpeed`` below.
"""

from __future__ import annotations

import time

from ray.rllib.callbacks.callbacks import RLlibCallback


def gpu_shares(gpus: int, runners: int, learners: int) -> tuple[float, float]:
    """The share of a GPU each env runner and each learner asks Ray for. One runner per GPU with its learner:
    just over half for the runners, which Algorithm.setup places first, so no two runners share a GPU, and the
    rest for the learners, so each fits only beside a runner, one per GPU. Halves let Ray pack two learners on
    one GPU, which NCCL refuses ("Duplicate GPU detected", seen on a 4-H200 host). Runners set apart from the
    GPUs share half of them, beside at most one learner (train_with refuses other runner counts on several GPUs,
    whose learners Ray could pack together); a learner in this process (``learners`` 0) has its GPU."""
    if learners > 1 and runners == learners:
        return 0.51, 0.49
    return (0.5 * gpus / runners if runners else 0.0), (0.5 if runners else 1.0)


def rllib_config(args, num_envs: int, horizon: int, gpu: bool, env_name: str, env_config: dict | None = None):
    """RLlib's PPO (new API stack) with rl_games' published Ant/Humanoid numbers, or the flags' numbers."""
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.connectors.env_to_module import MeanStdFilter

    humanoid = args.task == "Humanoid"
    runners, learners = args.env_runners, (args.gpus if args.gpus > 1 else 0)  # 0: in this process
    batch = max(runners, 1) * num_envs * horizon // max(learners, 1)  # every runner's rollout, split over the learners
    runner_share, learner_share = gpu_shares(args.gpus, runners, learners) if gpu else (0, 0)
    cpus = 1.0
    if runners or learners:  # the actors' CPU requests must fit the cluster, or Ray waits for CPUs forever
        import ray

        cpus = max(0.01, min(1.0, (ray.cluster_resources().get("CPU", 1.0) - 1.0) / (runners + learners)))
    config = (PPOConfig()
              .environment(env_name, env_config=env_config or {})
              .env_runners(num_env_runners=runners, num_envs_per_env_runner=num_envs,
                           rollout_fragment_length=horizon, gym_env_vectorize_mode="vector_entry_point",
                           num_gpus_per_env_runner=runner_share, num_cpus_per_env_runner=cpus,
                           env_to_module_connector=lambda env, spaces=None, device=None: MeanStdFilter())
              .learners(num_learners=learners, num_gpus_per_learner=learner_share,
                        num_cpus_per_learner=cpus if learners else "auto")
              .training(train_batch_size_per_learner=batch,
                        minibatch_size=args.batch_size or min(32768, max(batch // 4, 1)),
                        num_epochs=args.repeat_times or (5 if humanoid else 4),
                        lr=args.learning_rate or (5e-4 if humanoid else 3e-4), gamma=0.99, lambda_=0.95,
                        clip_param=0.2, vf_clip_param=1e6,  # RLlib's default clips value errors at 10 reward units
                        kl_coeff=0.0, entropy_coeff=0.0, grad_clip=1.0, vf_loss_coeff=1.0)
              .rl_module(model_config={"fcnet_hiddens": [400, 200, 100] if humanoid else [256, 128, 64],
                                       "fcnet_activation": "elu", "vf_share_layers": False})
              .debugging(seed=args.seed))
    if runners:
        config = config.callbacks(ForwardSpeed)
    return config


def _start_ray(actors: int = 0) -> None:
    import os

    import ray

    if not ray.is_initialized():
        # each env runner and learner actor asks Ray for a CPU: on a small machine, let them share
        ray.init(num_cpus=max(os.cpu_count() or 1, actors + 1), include_dashboard=False, log_to_driver=False,
                 configure_logging=False)


def run_rllib(env, args, horizon: int, run_dir: str) -> None:
    """One env runner in this process, stepping ``env`` (an ``RllibVecEnv``)."""
    from warpgym.wrappers.common import base_env
    from warpgym.wrappers.rllib import register_built_env

    base = base_env(env)
    _start_ray()
    name = register_built_env(f"warpgym-train-with-{args.task}", env)
    algo = rllib_config(args, base.num_envs, horizon, str(base.device).startswith("cuda"), name).build_algo()
    args.learner_object, args.rllib_results = algo, []
    try:
        for _ in range(args.iterations):
            args.rllib_results.append(algo.train())
    except RuntimeError as error:  # RLlib's env runner re-raises whatever the env raised as a bare RuntimeError
        stop = _time_limit_in(error)
        if stop is None:
            raise
        raise stop from None
    finally:
        algo.stop()


def _time_limit_in(error: BaseException | None):
    """The ``TimeLimitReached`` that ``error`` was raised from, if any (the run's --time-limit, not a fault)."""
    from warpgym.wrappers.common import TimeLimitReached

    while error is not None and not isinstance(error, TimeLimitReached):
        error = error.__cause__ or error.__context__
    return error


def run_rllib_remote(args, horizon: int, num_envs: int, device: str, run_dir: str, sink, start: float) -> str:
    """``args.env_runners`` env runners (and ``args.gpus`` learners, past one) as Ray actors; a row per RLlib
    iteration to ``sink``.
    Returns what stopped the run: "iterations" or "time limit"."""
    from warpgym.wrappers.rllib import register_rllib_env

    _start_ray(actors=args.env_runners + (args.gpus if args.gpus > 1 else 0))
    gpu = device.startswith("cuda")
    env_config = {"task": args.task, "device": "cuda:0" if gpu else "cpu", "seed": args.seed,
                  "max_episode_steps": args.episode_length}  # each actor sees its one GPU as cuda:0
    algo = rllib_config(args, num_envs, horizon, gpu, register_rllib_env(), env_config).build_algo()
    args.learner_object, args.rllib_results = algo, []
    last = time.time()
    try:
        for _ in range(args.iterations):
            result = algo.train()
            args.rllib_results.append(result)
            now = time.time()
            runners = result.get("env_runners", {})
            row = {"samples": int(result.get("num_env_steps_sampled_lifetime", 0)), "steps_s": now - last,
                   "time_s": now - start, "samples_per_s": args.env_runners * num_envs * horizon / max(now - last, 1e-9),
                   "episodes": int(runners.get("num_episodes", 0))}
            if row["episodes"]:
                row.update({"return": float(runners["episode_return_mean"]),
                            "length": float(runners["episode_len_mean"]),
                            "speed": float(runners.get("warpgym_forward_speed", float("nan")))})
            last = now
            sink(row)
            if args.time_limit is not None and now - start >= args.time_limit:
                return "time limit"
    finally:
        algo.stop()
    return "iterations"


class ForwardSpeed(RLlibCallback):
    """Logs warpgym's forward speed of every episode an env runner finishes (RLlib knows returns and
    lengths, not speeds): one host read per finished episode, beside RLlib's own per-env loop."""

    def on_episode_end(self, *, episode, env_runner=None, metrics_logger=None, env=None, env_index=0,
                       rl_module=None, **kwargs):
        from warpgym.wrappers.common import base_env

        speed = base_env(env.unwrapped).info["episode"]["s"][env_index]
        metrics_logger.log_value("warpgym_forward_speed", float(speed), reduce="mean")
