"""Multi-GPU scaling of PPO training on one host: throughput, where the time goes, and learning.

    python benchmarks/scaling.py --out OUT --task Ant --gpus 1 2 --seconds 60
    python benchmarks/scaling.py --out OUT --task Humanoid --gpus 1 2 4 --seconds 90

For one task it runs, with the same envs per GPU and a warm kernel cache:
  1 GPU    one `scripts/train.py` run on each GPU of the host, side by side (seeds 0, 1, ...): the
           baseline is their median, taken while the other GPUs are busy too, as in a G-GPU run;
  G GPUs   `torchrun --nproc_per_node=G scripts/train.py` for each G > 1 in --gpus;
  comms    the iteration's collectives alone (the gradient/KL all-reduce of every mini-batch, the
           normaliser and statistics all-reduces), replayed from a CUDA graph: their cost with no
           waiting on a slower peer.
It writes OUT/scaling_<task>.json and .md (throughput, speed-up, per-iteration phase times) and the
two figures OUT/<task>_gpus_reward_vs_time.png and ..._vs_samples.png; the run directories (metrics,
summaries, logs; no checkpoints) go into OUT/runs_<task>.tar.gz. `--comms-worker CHECKPOINT` is the comms
measurement itself, started by this script under torchrun.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tarfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

PHASES = ("idle", "collect", "normalizer", "update", "statistics")


def run(cmd: list[str], log: str, env: dict | None = None) -> subprocess.Popen:
    with open(log, "w") as f:
        return subprocess.Popen(cmd, cwd=ROOT, stdout=f, stderr=subprocess.STDOUT, env={**os.environ, **(env or {})})


def wait(procs: list[subprocess.Popen], logs: list[str]) -> None:
    for p, log in zip(procs, logs):
        if p.wait() != 0:
            with open(log) as f:
                tail = f.read()[-3000:]
            raise SystemExit(f"{' '.join(map(str, p.args))} failed ({p.returncode}):\n{tail}")


TRAIN_FLAGS: list[str] = []  # --train-flags: passed to every training run


def train_args(task: str, num_envs: int, seconds: float, run_dir: str, seed: int) -> list[str]:
    return ["scripts/train.py", "--task", task, "--num-envs", str(num_envs), "--time-limit", str(seconds),
            "--eval-gap", "10", "--seed", str(seed), "--run-dir", run_dir, "--no-plots", *TRAIN_FLAGS]


def summary_of(run_dir: str) -> dict:
    with open(os.path.join(run_dir, "summary.json")) as f:
        return json.load(f)


def run_shape(checkpoint: str) -> dict:
    """What a run's collectives carry, read from its checkpoint: the policy's sizes and how many
    mini-batch steps (one gradient all-reduce each) an iteration makes on each process."""
    import torch  # noqa: PLC0415

    from agents.checkpoint import load  # noqa: PLC0415

    ckpt = load(checkpoint, torch.device("cpu"))
    cfg = ckpt["config"]
    samples = cfg["env_args"]["num_envs"] * cfg["horizon_len"]
    return {"num_obs": ckpt["spec"]["num_obs"], "num_actions": ckpt["spec"]["num_actions"],
            "net_dims": tuple(cfg["net_dims"]), "steps": cfg["repeat_times"] * (samples // cfg["batch_size"])}


def comms_worker(checkpoint: str, out: str, replays: int = 50) -> None:
    """Under torchrun: time one iteration's collectives of the run that wrote ``checkpoint``,
    captured in a CUDA graph, on this host."""
    import torch  # noqa: PLC0415
    import torch.distributed as dist  # noqa: PLC0415

    from agents.actor_critic import ActorCritic  # noqa: PLC0415
    from agents.distributed import Workers, init_workers  # noqa: PLC0415

    local = int(os.environ["LOCAL_RANK"])
    device = torch.device(f"cuda:{local}")
    torch.cuda.set_device(device)
    init_workers("nccl", device)
    workers = Workers()
    shape = run_shape(checkpoint)
    num_obs, steps = shape["num_obs"], shape["steps"]
    policy = ActorCritic(num_obs, shape["num_actions"], shape["net_dims"]).to(device)
    for p in policy.parameters():
        p.grad = torch.randn_like(p)
    kl = torch.zeros((), device=device)
    moments = torch.zeros(2 * num_obs + 1, dtype=torch.float64, device=device)
    sums = torch.zeros(6, dtype=torch.float64, device=device)

    def iteration():
        workers.sum_(moments)
        for _ in range(steps):
            workers.mean_grads_(policy.parameters(), kl)
        workers.sum_(sums)

    side = torch.cuda.Stream(device)
    side.wait_stream(torch.cuda.current_stream(device))
    with torch.cuda.stream(side):
        iteration()
    torch.cuda.current_stream(device).wait_stream(side)
    graph = torch.cuda.CUDAGraph()
    with torch.cuda.graph(graph, capture_error_mode="thread_local"):
        iteration()
    times = []
    for _ in range(5):
        dist.barrier()
        start, end = torch.cuda.Event(enable_timing=True), torch.cuda.Event(enable_timing=True)
        start.record()
        for _ in range(replays):
            graph.replay()
        end.record()
        end.synchronize()
        times.append(start.elapsed_time(end) / replays)
    del graph  # a graph holding NCCL work must go before its communicator
    if workers.is_main:
        with open(out, "w") as f:
            json.dump({"ms_per_iteration": statistics.median(times), "all_reduces_per_iteration": steps + 2,
                       "gradient_floats": sum(p.numel() for p in policy.parameters()) + 1}, f)
    dist.destroy_process_group()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--task", default="Ant", choices=["Ant", "Humanoid"])
    ap.add_argument("--gpus", type=int, nargs="+", default=None, help="GPU counts (default: 1 and every GPU)")
    ap.add_argument("--num-envs", type=int, default=4096, help="envs per GPU")
    ap.add_argument("--seconds", type=float, default=60.0, help="wall-clock length of each training run")
    ap.add_argument("--train-flags", default="", help="more scripts/train.py flags, e.g. '--no-cuda-graph'")
    ap.add_argument("--report-only", action="store_true",
                    help="rewrite the table and figures in --out from its scaling_<task>.json and runs_<task>.tar.gz")
    ap.add_argument("--comms-worker", metavar="CHECKPOINT", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.gpus and min(args.gpus) < 1:
        ap.error(f"--gpus {' '.join(map(str, args.gpus))}: each is a number of GPUs, 1 or more")
    if args.num_envs < 1 or not args.seconds > 0:
        ap.error(f"--num-envs {args.num_envs} and --seconds {args.seconds}: both must be positive")
    TRAIN_FLAGS[:] = args.train_flags.split()
    if args.comms_worker:
        comms_worker(args.comms_worker, os.path.join(args.out, "comms.json"))
        return 0
    if args.report_only:
        return report(os.path.abspath(args.out), args.task)

    import torch  # noqa: PLC0415

    available = torch.cuda.device_count()
    gpus = sorted(set(args.gpus or [1, available]))
    if available < 1 or max(gpus) > available:
        raise SystemExit(f"--gpus {' '.join(map(str, gpus))}: this host has {available} GPU(s); pass counts up to "
                         f"{available}" + (" (scaling.py measures GPUs; run it on a GPU machine)" if not available else ""))
    out = os.path.abspath(args.out)
    runs = os.path.join(out, f"runs_{args.task}")
    os.makedirs(runs, exist_ok=True)
    task, n = args.task, args.num_envs
    say = lambda s: print(f"[{time.strftime('%H:%M:%S')}] {s}", flush=True)  # noqa: E731

    say(f"warm-up: {task} compiles its kernels once, so every timed run starts on a warm cache")
    warm = os.path.join(runs, "warmup")
    wait([run([sys.executable, "scripts/train.py", "--task", task, "--num-envs", "256", "--max-iterations", "3",
               "--run-dir", warm, "--no-plots"], warm + ".log", {"CUDA_VISIBLE_DEVICES": "0"})], [warm + ".log"])

    results: dict = {"task": task, "num_envs_per_gpu": n, "seconds": args.seconds, "train_flags": TRAIN_FLAGS,
                     "gpus": {}}
    say(f"1 GPU: {available} runs side by side, one per GPU")
    dirs = [os.path.join(runs, f"gpu1_seed{k}") for k in range(available)]
    procs = [run([sys.executable, *train_args(task, n, args.seconds, d, k)], d + ".log",
                 {"CUDA_VISIBLE_DEVICES": str(k)}) for k, d in enumerate(dirs)]
    wait(procs, [d + ".log" for d in dirs])
    results["gpus"]["1"] = {"runs": {os.path.basename(d): summary_of(d) for d in dirs}}
    for g in [g for g in gpus if g > 1]:
        say(f"{g} GPUs: torchrun")
        d = os.path.join(runs, f"gpu{g}")
        torchrun = [sys.executable, "-m", "torch.distributed.run", "--standalone", f"--nproc_per_node={g}"]
        wait([run([*torchrun, *train_args(task, n, args.seconds, d, 0)], d + ".log",
                  {"CUDA_VISIBLE_DEVICES": ",".join(map(str, range(g)))})], [d + ".log"])
        results["gpus"][str(g)] = {"runs": {os.path.basename(d): summary_of(d)}}
        say(f"{g} GPUs: the collectives alone")
        wait([run([*torchrun, "benchmarks/scaling.py", "--comms-worker", os.path.join(d, "checkpoint.pt"),
                   "--out", runs], os.path.join(runs, f"comms{g}.log"))], [os.path.join(runs, f"comms{g}.log")])
        with open(os.path.join(runs, "comms.json")) as f:
            results["gpus"][str(g)]["comms"] = json.load(f)

    for g, entry in results["gpus"].items():
        summaries = list(entry["runs"].values())
        entry["samples_per_s"] = statistics.median(s["steady_samples_per_s_median"] for s in summaries)
        entry["phase_ms"] = {p: 1e3 * statistics.median(s["steady_phase_s_median"].get(f"phase/{p}_s", 0.0)
                                                        for s in summaries) for p in (*PHASES,)}
        entry["phase_ms"]["iteration"] = 1e3 * statistics.median(s["steady_phase_s_median"]["iteration_s"]
                                                                 for s in summaries)
        entry["final_eval"] = [s.get("best_eval") for s in summaries]
    base = results["gpus"]["1"]["samples_per_s"]
    for entry in results["gpus"].values():
        entry["speedup"] = entry["samples_per_s"] / base
    results["device"] = next(iter(results["gpus"]["1"]["runs"].values()))["device"]
    with tarfile.open(os.path.join(out, f"runs_{task}.tar.gz"), "w:gz") as tar:
        tar.add(runs, arcname=f"runs_{task}",
                filter=lambda ti: None if ti.name.endswith(".pt") or "/tensorboard" in ti.name else ti)
    write_report(out, runs, results)
    shutil.rmtree(runs)
    return 0


def write_report(out: str, runs: str, results: dict) -> None:
    """scaling_<task>.json and .md and the two figures, from the results and the run directories."""
    task = results["task"]
    results["learning"] = learning_table(runs, results)
    with open(os.path.join(out, f"scaling_{task}.json"), "w") as f:
        json.dump(results, f, indent=1)
    table = markdown(results)
    with open(os.path.join(out, f"scaling_{task}.md"), "w") as f:
        f.write(table)
    figures(runs, out, results)
    print(table, flush=True)


def report(out: str, task: str) -> int:
    with open(os.path.join(out, f"scaling_{task}.json")) as f:
        results = json.load(f)
    with tarfile.open(os.path.join(out, f"runs_{task}.tar.gz")) as tar:
        tar.extractall(out, filter="data")
    runs = os.path.join(out, f"runs_{task}")
    write_report(out, runs, results)
    shutil.rmtree(runs)
    return 0


def mark_times(seconds: float) -> list[int]:
    return [t for t in (20, 30, 45, 60, 90, 120, 180, 300) if t <= seconds + 5]


def learning_table(runs: str, results: dict) -> dict:
    """Each run's latest evaluation (deterministic policy) at a few common wall-clock times."""
    from agents.logger import read_metrics  # noqa: PLC0415

    out = {}
    for g, entry in results["gpus"].items():
        for name in entry["runs"]:
            evals = [r for r in read_metrics(os.path.join(runs, name)) if "eval/return" in r]
            marks = {}
            for t in mark_times(results["seconds"]):
                before = [r for r in evals if r["time_s"] <= t]
                if before:
                    marks[str(t)] = {"eval/return": before[-1]["eval/return"], "eval/speed": before[-1]["eval/speed"],
                                     "samples": before[-1]["samples"]}
            out[f"{g} GPU{'s' if g != '1' else ''}: {name}"] = marks
    return out


def markdown(results: dict) -> str:
    g1 = results["gpus"]["1"]
    lines = [f"{results['task']}, {results['num_envs_per_gpu']} envs per GPU, {results['seconds']:.0f} s runs, "
             f"{results['device']}", "",
             "| GPUs | samples/s | speed-up | iteration ms | idle | collect | normaliser | update | statistics | "
             "collectives alone |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for g, e in sorted(results["gpus"].items(), key=lambda kv: int(kv[0])):
        ph = e["phase_ms"]
        comms = f"{e['comms']['ms_per_iteration']:.2f} ms ({e['comms']['all_reduces_per_iteration']} all-reduces)" \
            if "comms" in e else "-"
        lines.append(f"| {g} | {e['samples_per_s'] / 1e6:.3f} M | {e['speedup']:.3f}x | {ph['iteration']:.2f} | "
                     + " | ".join(f"{ph[p]:.2f}" for p in PHASES) + f" | {comms} |")
    times = [str(t) for t in mark_times(results["seconds"])]
    each = ", ".join(f"{r['steady_samples_per_s_median'] / 1e6:.3f} M" for r in g1["runs"].values())
    lines += ["", f"1-GPU baseline: median of {len(g1['runs'])} runs side by side, one per GPU ({each}).", "",
              "Latest evaluation (deterministic policy, 64 envs) by wall-clock time since process start:", "",
              "| run | " + " | ".join(f"{t} s" for t in times) + " |", "|---|" + "---:|" * len(times)]
    for name, marks in results["learning"].items():
        cells = [f"{m['eval/return']:.0f} @ {m['eval/speed']:.2f} m/s" if (m := marks.get(t)) else "-" for t in times]
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def figures(runs: str, out: str, results: dict) -> None:
    from agents.plotting import plot_runs  # noqa: PLC0415

    dirs, labels = [], []
    for g, entry in sorted(results["gpus"].items(), key=lambda kv: int(kv[0])):
        name = sorted(entry["runs"])[0]
        dirs.append(os.path.join(runs, name))
        labels.append(f"{g} GPU{'s' if g != '1' else ''}")
    tmp = os.path.join(runs, "figures")
    for path in plot_runs(dirs, tmp, labels, title=f"{results['task']}: PPO on 1 to {max(map(int, results['gpus']))} "
                                                   f"GPUs, {results['num_envs_per_gpu']} envs each"):
        shutil.copy(path, os.path.join(out, f"{results['task'].lower()}_gpus_{os.path.basename(path)}"))


if __name__ == "__main__":
    sys.exit(main())
