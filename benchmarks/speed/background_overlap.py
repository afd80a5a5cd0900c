"""Do the background evaluation's steps run beside the training's on a GPU? (``Config.eval_background``)

Walker2d-v5's evaluation sweep (docs/history.md, "Walker2d-v5's evaluations") found every iteration 0.12 s longer
with an evaluation beside it, on the training stream's own clock: about the evaluation chunk's own time, as if the
two ran one after the other. This times, on one GPU, one task at its preset's envs and the learning table's 64
evaluation envs, each the median of --repeats timings of --iterations, in one process:

  train    a training iteration alone (rollout and update, their graphs captured)
  eval     a chunk of the evaluation alone: 32 steps as one graph on its side stream, as the runner queued them
           after each iteration until 2026-11-27 (eager on a CPU)
  both     an iteration with a chunk queued after it
  launch   the host's time in queuing one chunk right after an iteration was queued, nothing synchronised; "idle":
           the same call with the GPU idle (its own cost)
  interleaved
           an iteration as the runner now runs it with an evaluation under way: its rollout launches one
           evaluation step (a one-step graph, side stream) after each of its own steps (the collector's
           ``beside`` hook)

and ``overlap = (train + eval - both) / min(train, eval)``: 1 where the chunk hides wholly beside the iteration,
0 where the two take turns (the interleaved iteration's likewise, beside as many evaluation steps). On a GPU it
also reads the host's time in one replay call of graphs of each kind (the rollout's, the chunk's, torch's own,
one and four env steps, one evaluation step). Run it again under ``CUDA_DEVICE_MAX_CONNECTIONS=32`` to see whether
the streams' hardware queues are what serialises them (the variable is read when CUDA starts: one process each).

    python -m benchmarks.speed.background_overlap --task Walker2d-v5 --json OUT/a.json
    CUDA_DEVICE_MAX_CONNECTIONS=32 python -m benchmarks.speed.background_overlap --task Walker2d-v5 --json OUT/b.json
    python -m benchmarks.speed.background_overlap --report OUT/a.json OUT/b.json
    python -m benchmarks.speed.background_overlap --task Hopper-v5 --num-envs 16 --eval-envs 4 --iterations 2 \\
        --repeats 2 --device cpu --json OUT/smoke.json          # a smoke run: on a CPU nothing runs beside
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

from benchmarks.harness import read_report, write_json

# an evaluation that never ends within the timings: every call queues its steps
ENDLESS = 10**7


def measure(task: str, num_envs: int | None, eval_envs: int, iterations: int, repeats: int, device: str) -> dict:
    import torch  # noqa: PLC0415

    from agents import Config, OnPolicyRunner  # noqa: PLC0415
    from agents.background_eval import STEPS_PER_ITERATION, BackgroundEvaluation  # noqa: PLC0415
    from agents.collect import capture_rollout  # noqa: PLC0415
    from warpgym.cli.bench import timed as timings  # noqa: PLC0415
    from warpgym.envs import make_vec_env  # noqa: PLC0415
    from warpgym.tasks.registry import task_entry  # noqa: PLC0415

    dev = torch.device(device)
    num_envs = num_envs or task_entry(task).defaults("cuda" if dev.type == "cuda" else "cpu")[0]  # warpgym train's
    cfg = Config.from_preset(task_entry(task).preset)
    cfg = cfg.replace(minibatch_size=min(cfg.minibatch_size, num_envs * cfg.horizon_len))  # a smoke run's few envs
    env = make_vec_env(task, num_envs=num_envs, device=device, seed=0)
    runner = OnPolicyRunner(env, cfg, print_fn=lambda s: None)
    bg = BackgroundEvaluation(make_vec_env(task, num_envs=eval_envs, device=device, seed=1), runner.policy,
                              runner.normalizer, cfg.normalize_obs, ENDLESS, dev, capturable=dev.type == "cuda")

    def sync():
        if dev.type == "cuda":
            torch.cuda.synchronize(dev)

    for _ in range(3):  # the second iteration captures the rollout's and the update's graphs
        runner.iterate()
    bg.start(runner.policy, runner.normalizer, {})
    for _ in range(3):  # the first chunk runs eagerly; then the step's graph is captured and replayed
        bg.advance()
    if bg.graph is not None:  # the chunk as one 32-step graph on the side stream, as the runner queued it until
        chunk = capture_rollout("rollout", bg.play_step, lambda: None, STEPS_PER_ITERATION, dev)  # 2026-11-27

        def queue_chunk():
            with torch.cuda.stream(bg.stream):
                chunk.replay()
    else:  # eager: a chunk of steps, between the iterations
        chunk, queue_chunk = None, bg.advance
    sync()

    def timed(step) -> float:  # seconds a call, over ``iterations`` calls, the device synchronised around them
        return timings(step, iterations, 1, device)[0] / iterations

    def both():
        runner.iterate()
        queue_chunk()

    times = {name: [] for name in ("train", "eval", "both")}
    launch, launch_idle = [], []
    for _ in range(repeats):  # interleaved, so that a drift of the clocks touches all three alike
        times["train"].append(timed(runner.iterate))
        times["eval"].append(timed(queue_chunk))
        times["both"].append(timed(both))
        for _ in range(iterations):
            runner.iterate()
            t = time.perf_counter()
            queue_chunk()
            launch.append(time.perf_counter() - t)
        sync()
        for _ in range(iterations):  # the same call with nothing queued before it: the call's own cost
            t = time.perf_counter()
            queue_chunk()
            launch_idle.append(time.perf_counter() - t)
            sync()
    med = {name: statistics.median(v) for name, v in times.items()}
    replays = host_replays(runner, bg, chunk, iterations, dev) if chunk is not None else {}
    woven = interleaved(runner, bg, timed, repeats)
    return {"task": task, "num_envs": runner.spec.num_envs, "eval_envs": eval_envs,
            "steps_per_chunk": STEPS_PER_ITERATION, "captured": bg.graph is not None,
            "device": torch.cuda.get_device_name(dev) if dev.type == "cuda" else "cpu",
            "max_connections": os.environ.get("CUDA_DEVICE_MAX_CONNECTIONS", "default (8)"),
            "iterations": iterations, "repeats": repeats, "times_s": times, "median_s": med,
            "launch_s": statistics.median(launch), "launch_idle_s": statistics.median(launch_idle),
            "host_replay_s": replays,
            "overlap": overlap_of(med["train"], med["eval"], med["both"]),
            **({} if woven is None else {
                "interleaved_s": woven["seconds"], "horizon": woven["horizon"],
                # the same work as "both" when the horizon is the chunk's 32 steps; else scaled to it
                "overlap_interleaved": overlap_of(med["train"], med["eval"] * woven["horizon"] / STEPS_PER_ITERATION,
                                                  statistics.median(woven["seconds"]))}),
            "date": time.strftime("%Y-%m-%d"), "command": "python -m benchmarks.speed.background_overlap "
                                                           + " ".join(sys.argv[1:])}


def overlap_of(a: float, b: float, together: float) -> float:
    """How much of the shorter of two pieces of work hid beside the longer: 1 wholly, 0 not at all."""
    return (a + b - together) / min(a, b)


def interleaved(runner, bg, timed, repeats: int) -> dict | None:
    """Training iterations as the runner runs them with an evaluation under way: its steps one beside each of the
    rollout's (the collector's ``beside`` hook; on a GPU a one-step graph on the side stream after each of the
    rollout's step graphs), seconds an iteration, ``repeats`` timings. None where the rollout is captured whole
    (``--rollout-graph rollout``): it has no steps to weave into."""
    from agents.collect import WholeRollout  # noqa: PLC0415

    if isinstance(runner.collector.graph, WholeRollout):
        return None

    def iteration():
        runner.iterate()
        bg.advance()  # nothing queued: the rollout wove its steps in

    runner.collector.beside = bg.beside
    try:
        iteration()  # the first woven rollout
        return {"seconds": [timed(iteration) for _ in range(repeats)], "horizon": runner.storage.horizon}
    finally:
        runner.collector.beside = None


def host_replays(runner, bg, chunk, n: int, dev) -> dict:
    """The host's seconds in one replay call, the GPU idle before it (median of ``n``), for graphs of each kind: is a
    replay that holds the host the evaluation's own, any graph with MuJoCo Warp's step in it, or any on a side
    stream?"""
    import torch  # noqa: PLC0415

    def host(fn) -> float:
        out = []
        for _ in range(n):
            torch.cuda.synchronize(dev)
            t = time.perf_counter()
            fn()
            out.append(time.perf_counter() - t)
        torch.cuda.synchronize(dev)
        return statistics.median(out)

    def on_side(fn):
        def call():
            with torch.cuda.stream(bg.stream):
                fn()
        return call

    x = torch.randn(256, 256, device=dev)
    plain = torch.cuda.CUDAGraph()  # torch's kernels only: 400 small matmuls
    side = torch.cuda.Stream(dev)
    side.wait_stream(torch.cuda.current_stream(dev))
    with torch.cuda.stream(side):
        for _ in range(3):
            y = x @ x  # warm-up, as torch's capture asks
    torch.cuda.current_stream(dev).wait_stream(side)
    with torch.cuda.graph(plain):
        y = x
        for _ in range(400):
            y = (y @ x).tanh_()
    out = {"rollout_main": host(runner.collector.graph.replay), "eval_chunk_main": host(chunk.replay),
           "eval_chunk_side": host(on_side(chunk.replay)), "torch_only_side": host(on_side(plain.replay)),
           "torch_only_main": host(plain.replay)}
    # graphs of 1 and 4 of the eval env's steps, captured by torch and (the simulation alone) by Warp: does a graph
    # hold the host for its later steps whoever captured it?
    import warp as wp  # noqa: PLC0415

    env, act = bg.env, torch.zeros(bg.env.num_envs, bg.env.single_action_space.shape[0], device=dev)
    for k in (1, 4):
        g = torch.cuda.CUDAGraph()
        with torch.cuda.graph(g, capture_error_mode="thread_local"):
            for _ in range(k):
                env.step(act)
        out[f"torch_graph_{k}_steps"] = host(g.replay)
        with wp.ScopedCapture(device=str(dev)) as cap:
            for _ in range(k):
                env.sim.simulate()
        out[f"warp_graph_{k}_simulates"] = host(lambda graph=cap.graph: wp.capture_launch(graph))
    out["env_step_eager"] = host(lambda: env.step(act))
    out["eval_step_side"] = host(on_side(bg.graph.replay))  # the runner's: one evaluation step (measured since the
    return out                                             # sixth run)


def table(docs: list[dict]) -> str:
    woven = any("interleaved_s" in d for d in docs)  # measured since the fourth run
    lines = ["| task | device | CUDA_DEVICE_MAX_CONNECTIONS | envs / eval envs | train | eval chunk | both | launch "
             "(idle) | overlap |" + (" interleaved | its overlap |" if woven else ""),
             "|---|---|---|---|---:|---:|---:|---:|---:|" + ("---:|---:|" if woven else "")]
    for d in docs:
        m = d["median_s"]
        captured = "" if d["captured"] else " (eager)"
        idle = f" ({d['launch_idle_s'] * 1e3:.2f} ms)" if "launch_idle_s" in d else ""  # measured since the first run
        lines.append(f"| {d['task']} | {d['device']} | {d['max_connections']} | {d['num_envs']} / {d['eval_envs']} | "
                     f"{m['train'] * 1e3:.1f} ms | {m['eval'] * 1e3:.1f} ms{captured} | {m['both'] * 1e3:.1f} ms | "
                     f"{d['launch_s'] * 1e3:.2f} ms{idle} | {d['overlap']:.2f} |"
                     + ((f" {statistics.median(d['interleaved_s']) * 1e3:.1f} ms | {d['overlap_interleaved']:.2f} |"
                         if "interleaved_s" in d else " - | - |") if woven else ""))
    replayed = [d for d in docs if d.get("host_replay_s")]
    if replayed:  # measured since the second run
        names = list(dict.fromkeys(k for d in replayed for k in d["host_replay_s"]))  # older runs have fewer
        lines += ["", "host time of one replay call, the GPU idle before it (ms):", "",
                  "| device | CUDA_DEVICE_MAX_CONNECTIONS | " + " | ".join(names) + " |",
                  "|---|---|" + "---:|" * len(names)]
        for d in replayed:
            got = d["host_replay_s"]
            lines.append(f"| {d['device']} | {d['max_connections']} | "
                         + " | ".join(f"{got[k] * 1e3:.2f}" if k in got else "-" for k in names) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--task", default="Walker2d-v5")
    ap.add_argument("--num-envs", type=int, default=None, help="training envs (default: the preset's)")
    ap.add_argument("--eval-envs", type=int, default=64)
    ap.add_argument("--iterations", type=int, default=20, help="iterations (or chunks) per timing")
    ap.add_argument("--repeats", type=int, default=5, help="timings of each, the median reported")
    ap.add_argument("--device", default="cuda:0")
    ap.add_argument("--json", metavar="PATH", help="write the timings here")
    ap.add_argument("--report", nargs="+", metavar="JSON", help="print the table of earlier --json files")
    args = ap.parse_args(argv)
    if args.report:
        print(table([read_report(path, "a JSON this script wrote with --json") for path in args.report]))
        return 0
    if args.iterations < 1 or args.repeats < 1 or args.eval_envs < 1:
        ap.error(f"--iterations {args.iterations} / --repeats {args.repeats} / --eval-envs {args.eval_envs}: each "
                 "at least 1, e.g. --iterations 20 --repeats 5 --eval-envs 64")
    doc = measure(args.task, args.num_envs, args.eval_envs, args.iterations, args.repeats, args.device)
    if args.json:
        os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
        write_json(args.json, doc)
    print(table([doc]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
