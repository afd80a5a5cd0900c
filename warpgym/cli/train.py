"""Train PPO on a warpgym task and show episodic reward against wall-clock time and against samples.

    warpgym train --task Ant                       # GPU: 8192 envs; CPU: 64 envs, a 1-minute demo
    warpgym train --task Humanoid --time-limit 300
    warpgym train --resume runs/Ant-20261122-120000 --max-iterations 800
    torchrun --nproc_per_node=4 -m warpgym train --task Ant  # 4 GPUs, one policy, 8192 Ants on each (grow-kl)

A run directory holds config.json, metrics.jsonl/.csv, tensorboard/, checkpoint.pt (written
atomically every --save-gap iterations and at the end), summary.json, and the two plots
reward_vs_time.png and reward_vs_samples.png.
"""

from __future__ import annotations

import os
import sys
import time

from agents import Config, OnPolicyRunner
from agents.algos import by_agent
from agents.data_parallel import kl_target
from warpgym.cli import process_start_time, train_args, write_json
from warpgym.cli.run_setup import RunPlan, configure, device_kind, plan_run

# The wall-clock axis starts when the process did: the interpreter, imports and kernel compiles count.
PROCESS_START = process_start_time()

def parse_args(argv=None):
    return train_args.parse_args(argv, __doc__)


def summarize(history: list[dict], device_name: str, cfg: Config) -> dict:
    """Steady-state throughput and the first time each forward speed was reached."""
    from agents.logger import first_reaching, steady_median  # noqa: PLC0415

    rows = history[len(history) // 5 :]
    workers = int(os.environ.get("WORLD_SIZE", "1"))
    out = {"device": device_name, "agent": cfg.agent, "num_envs": cfg.env_args["num_envs"],
           "iterations": len(history), "workers": workers, "num_envs_total": cfg.env_args["num_envs"] * workers,
           "steady_samples_per_s_median": steady_median(history) or 0.0}
    if cfg.agent == "AgentPPO":
        out.update(multi_gpu=cfg.multi_gpu, kl_target=kl_target(cfg.multi_gpu, cfg.desired_kl, workers),
                   horizon_per_process=cfg.process_horizon(workers))
    phases = sorted({k for r in rows for k in r if k.startswith("phase/")} | {"iteration_s"})
    out["steady_phase_s_median"] = {k: steady_median(history, k) for k in phases if any(k in r for r in rows)}
    if history:
        out["final"] = {k: history[-1].get(k) for k in ("time_s", "samples", "return", "speed")}
    evals = [r for r in history if "eval/return" in r]
    if evals:
        best = max(evals, key=lambda r: r["eval/return"])
        out["best_eval"] = {k: best[k] for k in ("time_s", "samples", "eval/return", "eval/speed")}
        for v in (1.0, 2.0, 3.0):
            out[f"first_eval_speed_{v:g}ms"] = first_reaching(evals, "eval/speed", v)
    for v in (1.0, 2.0, 3.0):  # training episodes (stochastic policy), logged every iteration
        out[f"first_train_speed_{v:g}ms"] = first_reaching(history, "speed", v)
    out["first_iteration_time_s"] = history[0]["time_s"] if history else None
    return out


def start_workers(args) -> tuple[int, str | None]:
    """Under torchrun (WORLD_SIZE > 1): join the process group; return (rank, this process's device).

    On several machines each process takes the GPU of its LOCAL_RANK, and ranks are global."""
    if int(os.environ.get("WORLD_SIZE", "1")) <= 1:
        return 0, args.device
    import torch  # noqa: PLC0415
    import torch.distributed as dist  # noqa: PLC0415

    from agents.distributed import init_workers  # noqa: PLC0415

    local = int(os.environ.get("LOCAL_RANK", "0"))
    on_cpu = args.device == "cpu" or (args.device is None and not torch.cuda.is_available())
    if on_cpu:
        init_workers("gloo")
        return dist.get_rank(), "cpu"
    if local >= torch.cuda.device_count():
        raise SystemExit(f"LOCAL_RANK={local} but this machine has {torch.cuda.device_count()} GPUs: "
                         "pass torchrun --nproc_per_node <= the number of GPUs")
    torch.cuda.set_device(local)
    init_workers("nccl", torch.device(f"cuda:{local}"))
    return dist.get_rank(), f"cuda:{local}"


def watch_peers(rank: int):
    """Under torchrun, end this process with a message when another worker goes silent (see
    agents.distributed.PeerWatch); WARPGYM_PEER_TIMEOUT sets the seconds of silence allowed."""
    from agents.distributed import PeerWatch, job_store  # noqa: PLC0415

    size = int(os.environ.get("WORLD_SIZE", "1"))
    store = job_store() if size > 1 else None
    if store is None:
        return None
    timeout = float(os.environ.get("WARPGYM_PEER_TIMEOUT", "30"))
    return PeerWatch(store, rank, size, timeout=timeout)


def resume_hint(run_dir: str) -> str:
    """How to go on, as rank 0 sees it (its machine holds the checkpoint)."""
    if not os.path.isfile(os.path.join(run_dir, "checkpoint.pt")):
        return f"No checkpoint was written to {run_dir} yet."
    return (f"The run's last checkpoint is in {run_dir}; continue it with: warpgym train --resume "
            f"{run_dir} (or torchrun ... -m warpgym train --resume {run_dir}, on any number of GPUs)")


def main(argv=None) -> int:
    import signal  # noqa: PLC0415

    import torch.distributed as dist  # noqa: PLC0415

    args = parse_args(argv)
    rank, args.device = start_workers(args)
    watch = watch_peers(rank)
    live: dict = {}  # train() puts its runner here, for the signal handler

    def on_signal(signum, frame):
        runner = live.get("runner")
        if runner is None or runner.stop_requested:
            raise SystemExit(128 + signum)
        # Ctrl-C, a cluster's pre-emption, or torchrun ending the job because a worker failed
        sys.stderr.write(f"\nwarpgym worker {rank}: signal {signum}: stopping after this iteration and saving "
                         "(send it again to stop at once)\n")
        runner.request_stop()

    previous = {s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
    finished = False
    try:
        code = train(args, rank, watch, live)
        finished = True
        return code
    except BaseException as e:
        # status 2 is a flag's error (warpgym.cli.flags): nothing started, its one line says it all
        if args.run_dir and not (isinstance(e, SystemExit) and e.code in (0, None, 2)):
            # torchrun's SIGTERM, after a peer died, can come while this line is written: it must not cut it
            for sig in previous:
                signal.signal(sig, signal.SIG_IGN)
            why = f"{type(e).__name__}: {str(e).splitlines()[0][:300]}" if str(e) else type(e).__name__
            hint = resume_hint(args.run_dir) if rank == 0 else "Rank 0's output says how to resume."
            sys.stderr.write(f"\nwarpgym worker {rank}: training stopped ({why}). {hint}\n")
        raise
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        if watch is not None:
            watch.stop(finished=finished)
        if dist.is_available() and dist.is_initialized():
            dist.destroy_process_group()


def built(make, what: str, phase):
    """``make()``, with one timeline line: how long it took and what Warp compiled meanwhile."""
    from warpgym.compile.log import describe_compiles, mark  # noqa: PLC0415

    start, before = time.time(), mark()
    obj = make()
    parts = getattr(getattr(obj, "sim", None), "build_times", {})
    parts = f" ({', '.join(f'{k} {v:.1f} s' for k, v in parts.items() if v >= 0.05)})" if parts else ""
    phase(f"{what} built in {time.time() - start:.1f} s{parts}; {describe_compiles(before)}")
    return obj


class Startup:
    """What a start-up says as it goes (a cold start should say where its time goes, not sit silent), with
    the seconds since the process started; summary.json keeps the timeline."""

    def __init__(self, say):
        from warpgym.compile import preload  # noqa: PLC0415

        self.say, self.timeline = say, []
        note = preload.bytecode_note()
        if note:
            say(f"note: {note}", flush=True)
        self.cache, self.cached = preload.kernel_cache()
        self.phase(f"imports done; Warp kernel cache {self.cache} holds {self.cached} modules"
                   + ("" if self.cached else " (empty: this run compiles them, about 15 s on an H100 or on two "
                                             "CPU cores; WARP_CACHE_PATH points Warp at a shared cache)"))

    def phase(self, text: str) -> None:
        self.timeline.append((round(time.time() - PROCESS_START, 2), text))
        self.say(f"[{self.timeline[-1][0]:6.1f} s] {text}", flush=True)

    def record(self) -> dict:
        from warpgym.compile import log as compile_log  # noqa: PLC0415

        return {"timeline": self.timeline, "kernel_cache": self.cache, "cached_modules_at_start": self.cached,
                "compiled": compile_log.compile_trace(since=PROCESS_START),
                "lto_builds": compile_log.lto_builds_since(PROCESS_START)}


def make_runner(args, plan: RunPlan, cfg: Config, startup: Startup) -> tuple[OnPolicyRunner, object]:
    """The training env, the evaluation env (none under --no-eval or on ranks above 0) and the runner that
    holds them. Returns the runner and the training env."""
    from warpgym.envs.graph_env import GraphVecEnv  # noqa: PLC0415

    env = built(lambda: cfg.env_class(**cfg.env_args), f"training env: {plan.task} x {cfg.env_args['num_envs']}",
                startup.phase)
    eval_env = None if args.no_eval else built(lambda: cfg.eval_env_class(**cfg.eval_env_args),
                                               f"evaluation env: {plan.task} x {cfg.eval_env_args['num_envs']}",
                                               startup.phase)
    assert isinstance(env, GraphVecEnv)
    recorder = None
    if args.video and eval_env is not None:
        from warpgym.media.clips import EvalVideoRecorder  # noqa: PLC0415

        recorder = EvalVideoRecorder(plan.run_dir, steps=args.video_length, every=args.video_every,
                                     print_fn=lambda s: print(s, flush=True))
    common = dict(run_dir=plan.run_dir, eval_env=eval_env, start_time=PROCESS_START,
                  print_fn=lambda s: print(s, flush=True), profile=args.profile, cuda_graph=not args.no_cuda_graph,
                  eval_recorder=recorder)
    if cfg.agent == "AgentPPO":
        common["rollout_graph"] = args.rollout_graph or "step"
        ready = ("policy and optimiser ready; the first iterations capture the update graph and the rollout's "
                 "({}: agents.collect)")
    else:
        ready = (f"policy, critics, replay and optimisers ready; after {cfg.learning_starts} steps each env step and "
                 "its updates are captured ({}: agents.sac.runner)")
    runner = by_agent(cfg.agent).runner(env, cfg, **common)
    startup.phase(ready.format(runner.capture))
    return runner, env


def resume(runner: OnPolicyRunner, plan: RunPlan, say) -> None:
    """A resumed run goes on from its checkpoint; one stopped before its first save starts again."""
    if plan.has_checkpoint:
        runner.load(os.path.join(plan.run_dir, "checkpoint.pt"), resume=True)
        say(f"resumed at iteration {runner.iteration} ({runner.samples} samples)", flush=True)
    else:
        runner.logger.drop_rows_after(0, 0)
        say(f"{plan.run_dir} has no checkpoint yet: the run starts again from iteration 0", flush=True)


def run_summary(args, history: list[dict], device_name: str, cfg: Config, runner: OnPolicyRunner, env,
                startup: Startup) -> dict:
    """summary.json: throughput and targets (summarize), then what this run alone knows."""
    summary = summarize(history, device_name, cfg)
    summary["solver_load"] = env.sim.solver_load()  # this process's envs, over the whole run
    summary["kept_checkpoints"] = runner.kept
    summary["resumes"] = runner.resumes  # where later processes took the run over (warpgym train --resume)
    if cfg.target:
        summary["target"] = {"target": cfg.target, "reached": runner.target_reached}
    # the capture the rollouts had: "off" where the device cannot capture or a capture failed and fell back
    summary["rollout_graph"] = runner.capture
    summary["startup"] = startup.record()
    summary["faults"] = {k[len("faults/"):]: v for k, v in (history[-1] if history else {}).items()
                         if k.startswith("faults/")}
    if args.profile:
        summary["profile"] = runner.timer.table()
        print("| phase | ms / iteration | share |\n|---|---:|---:|")
        for p in summary["profile"]:
            print(f"| {p['phase']} | {p['ms_per_iteration']:.2f} | {100 * p['share']:.1f}% |")
    return summary


def train(args, rank: int, watch=None, live: dict | None = None) -> int:
    """One process's share of a run: plan it, configure it, build the runner, learn, and on rank 0 write the
    summary, the plots and the closing line."""
    import torch  # noqa: PLC0415

    import warpgym  # noqa: PLC0415,F401  (registers the envs, quiets Warp)

    processes = int(os.environ.get("WORLD_SIZE", "1"))
    plan = plan_run(args, rank)
    cfg = configure(args, plan, rank, processes)
    args.run_dir = run_dir = plan.run_dir
    if rank == 0:
        os.makedirs(run_dir, exist_ok=True)
    if watch is not None:  # asked when a peer is lost, by which time a checkpoint may exist
        watch.hint = lambda: resume_hint(run_dir)
    cuda = device_kind(plan.device) == "cuda"
    device_name = torch.cuda.get_device_name(torch.device(plan.device)) if cuda else "cpu"
    if not args.resume and rank == 0:
        write_json(os.path.join(run_dir, "config.json"), {"task": plan.task, "device": plan.device,
                                                          "num_envs": plan.num_envs, "seed": args.seed,
                                                          **cfg.to_dict()})
    say = print if rank == 0 else (lambda *a, **k: None)
    shares = share_line(cfg, processes) if processes > 1 else ""
    learner = "PPO" if cfg.agent == "AgentPPO" else "SAC"
    say(f"warpgym {learner} | {plan.task} | {plan.num_envs} envs on {plan.device} ({device_name}){shares} | run dir "
        f"{run_dir}", flush=True)
    startup = Startup(say)
    if args.no_mathdx:
        from warpgym.compile import preload  # noqa: PLC0415

        preload.use_mathdx(False)
    runner, env = make_runner(args, plan, cfg, startup)
    if live is not None:
        live["runner"] = runner
    if args.resume:
        resume(runner, plan, say)
    try:
        history = runner.learn(args.max_iterations, args.total_steps, args.time_limit)
    finally:
        stopped = runner.stop_requested
        runner.close()
        if live is not None:
            live.clear()
    if watch is not None:  # every process has left the collectives: peers may end at their own pace
        watch.stop(finished=True)
    if rank > 0:
        return 0
    if args.resume:  # the summary speaks of the whole run (its rows on disk), not of this process's part of it
        from agents.logger import read_metrics  # noqa: PLC0415

        history = read_metrics(run_dir)
    summary = run_summary(args, history, device_name, cfg, runner, env, startup)
    summary["stopped_on_request"] = stopped  # a signal ended it before its budget: `--resume` goes on
    write_json(os.path.join(run_dir, "summary.json"), summary)
    if not args.no_plots:
        try:
            from agents.plotting import plot_runs  # noqa: PLC0415

            paths = plot_runs([run_dir], run_dir, labels=[f"{plan.task} {plan.num_envs} envs"],
                              title=f"warpgym {plan.task}")
            print("wrote " + ", ".join(paths), flush=True)
        except ImportError:
            print("matplotlib is not installed: pip install 'warpgym[train]' for the plots", flush=True)
    if stopped:
        print(f"stopped on request after iteration {runner.iteration}. {resume_hint(run_dir)}", flush=True)
    print(closing_line(plan.task, run_dir, summary), flush=True)
    return 0


def share_line(cfg: Config, processes: int) -> str:
    """How PPO's processes divide the run (the header's middle)."""
    local_envs = cfg.env_args["num_envs"]
    widened = kl_target(cfg.multi_gpu, cfg.desired_kl, processes)
    steps = cfg.process_horizon(processes)
    return (f" x {processes} processes, {local_envs} envs each (--multi-gpu {cfg.multi_gpu}: "
            f"{local_envs * processes} in all" + (f", {steps} of horizon_len {cfg.horizon_len} steps each"
                                                  if steps != cfg.horizon_len else "")
            + (f", KL target {widened:g}" if widened != cfg.desired_kl else "") + ")")


def closing_line(task: str, run_dir: str, summary: dict) -> str:
    """What a person reads last: how far the run got, its best evaluation, and the next command."""
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    entry = task_entry(task)
    final = summary.get("final") or {}
    m, s = divmod(int(final.get("time_s") or 0), 60)
    best = summary.get("best_eval")
    result = (f"its best evaluation returned {best['eval/return']:.1f}"
              + (f" at {best['eval/speed']:.2f} m/s" if entry.reports_speed else "") if best else "it was not evaluated")
    score = f"warpgym eval {run_dir} scores it in {entry.scored_in}; "
    n = final.get("samples") or 0
    samples = f"{n / 1e6:.1f} M" if n >= 1e6 else f"{n / 1e3:.1f} k"
    return (f"Trained {task} for {summary['iterations']} iterations ({samples} samples, "
            f"{m} min {s:02d} s); {result}. Next: {score}warpgym play {run_dir} --gif {task.lower()}.gif draws it "
            f"(the numbers: {os.path.join(run_dir, 'summary.json')}).")


if __name__ == "__main__":
    sys.exit(main())
