"""Several machines: K torchrun "nodes" on one host against one node of all its GPUs, the same training.

    python -m benchmarks.multi_gpu.nodes --out OUT --gpus 4 --nodes 2 --task Ant --seconds 60 --repeats 3
    python -m benchmarks.multi_gpu.nodes --out OUT --gpus 2 --nodes 2 --device cpu --num-envs 4 --seconds 15 --repeats 1
    python -m benchmarks.multi_gpu.nodes --report OUT/nodes.json [OUT2/nodes.json ...]   # the table, runs joined

One node: ``torchrun --standalone --nproc_per_node=G -m warpgym train ...``. K nodes: K torchrun agents, each
``--nnodes=K --nproc_per_node=G/K`` with its own G/K GPUs (``CUDA_VISIBLE_DEVICES``) and its share of the cores,
meeting through a c10d rendezvous whose store this script holds on a port the OS picked, as agents on K
machines would meet at one of them. Every process then takes GPU ``LOCAL_RANK`` of its node, and the ranks are
global. The two layouts take turns (one node first in even repeats, K nodes first in odd ones), so that a host
warming up favours neither. Each run trains without evaluations for --seconds; its speed is the steady median of
its logged samples/s (agents.logger.steady_median: the first fifth of the iterations left out). The figure is the
median over repeats of K nodes' speed over one node's; the target (issue 54) is within 5 %.

Writes OUT/nodes.json after every run and prints the table.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from datetime import timedelta

from agents.logger import read_metrics, steady_median
from benchmarks.harness import ROOT, child_env, core_shares, read_report, reported, visible_gpus, write_json

WITHIN = 0.05


def train_args(args, run_dir: str) -> list[str]:
    flags = ["--task", args.task, "--run-dir", run_dir, "--time-limit", str(args.seconds), "--no-eval", "--no-plots",
             "--seed", str(args.seed)]
    flags += ["--device", args.device] if args.device else []
    return flags + (["--num-envs", str(args.num_envs)] if args.num_envs else [])


def node_commands(args, run_dir: str, nodes: int, port: int | None) -> list[tuple[list[str], list[str], list[int]]]:
    """(command, its GPUs, its cores) for each torchrun agent of a layout of ``nodes`` nodes."""
    per_node = args.gpus // nodes
    gpus = visible_gpus(args.gpus) if args.device in (None, "cuda") else [str(k) for k in range(args.gpus)]
    cores = core_shares(nodes)
    rendezvous = f"nodes-{os.getpid()}-{time.time_ns()}"  # one id for the layout's agents, new for each run
    out = []
    for node in range(nodes):
        if nodes == 1:
            launch = ["--standalone", f"--nproc_per_node={per_node}"]
        else:
            launch = [f"--nnodes={nodes}", f"--nproc_per_node={per_node}", "--rdzv-backend=c10d",
                      f"--rdzv-endpoint=127.0.0.1:{port}", f"--rdzv-id={rendezvous}",
                      "--rdzv-conf=is_host=false"]
        cmd = [sys.executable, "-m", "torch.distributed.run", *launch, "-m", "warpgym", "train",
               *train_args(args, run_dir)]
        out.append((cmd, gpus[node * per_node:(node + 1) * per_node], cores[node]))
    return out


def run_layout(args, name: str, nodes: int) -> dict:
    """One training on ``nodes`` torchrun agents; its exit codes and steady samples/s."""
    import torch.distributed as dist  # noqa: PLC0415

    run_dir = os.path.join(args.out, "runs", name)
    store = None
    if nodes > 1:  # the rendezvous store, held here so that no agent races another for a port
        store = dist.TCPStore("127.0.0.1", 0, is_master=True, wait_for_workers=False, timeout=timedelta(seconds=120))
    procs = []
    started = time.time()
    for node, (cmd, gpus, cores) in enumerate(node_commands(args, run_dir, nodes, store.port if store else None)):
        env = child_env(OMP_NUM_THREADS="1")
        if args.device in (None, "cuda"):
            env["CUDA_VISIBLE_DEVICES"] = ",".join(gpus)
        log = open(os.path.join(args.out, "runs", f"{name}-node{node}.log"), "w")
        procs.append((subprocess.Popen(cmd, cwd=ROOT, stdout=log, stderr=subprocess.STDOUT, env=env,
                                       preexec_fn=lambda c=set(cores): os.sched_setaffinity(0, c)), log))
    codes = []
    for proc, log in procs:
        try:
            codes.append(proc.wait(timeout=args.seconds + 300))
        except subprocess.TimeoutExpired:
            proc.kill()
            codes.append(proc.wait())
        log.close()
    rows = read_metrics(run_dir) if os.path.isfile(os.path.join(run_dir, "metrics.jsonl")) else []
    return {"name": name, "nodes": nodes, "gpus": args.gpus, "exit_codes": codes, "iterations": len(rows),
            "samples_per_s": steady_median(rows), "wall_s": round(time.time() - started, 1)}


def summarize(data: dict) -> dict:
    """Each repeat's K-node over one-node speed, their median, and whether it is within the target."""
    by = {(r["repeat"], r["nodes"]): r["samples_per_s"] for r in data["rows"]}
    ratios = [by[(k, data["nodes"])] / by[(k, 1)] for k in sorted({r["repeat"] for r in data["rows"]})
              if by.get((k, 1)) and by.get((k, data["nodes"]))]
    ratio = statistics.median(ratios) if ratios else None
    return {"ratios": [round(x, 4) for x in ratios], "median_ratio": None if ratio is None else round(ratio, 4),
            "holds": ratio is not None and abs(1.0 - ratio) <= WITHIN}


def joined(paths: list[str]) -> dict:
    """Several runs' nodes.json as one: their repeats numbered on, the first's task and layout."""
    data = None
    for path in paths:
        more = read_report(path, "the nodes.json a run of this script wrote")
        if data is None:
            data = dict(more, rows=[])
        elif [more[k] for k in ("task", "gpus", "nodes")] != [data[k] for k in ("task", "gpus", "nodes")]:
            raise SystemExit(f"--report {path}: {more['task']}, {more['gpus']} processes in {more['nodes']} nodes, "
                             f"but the first has {data['task']}, {data['gpus']} in {data['nodes']}: join like runs")
        first = 1 + max((r["repeat"] for r in data["rows"]), default=-1)
        data["rows"] += [dict(r, repeat=first + r["repeat"]) for r in more["rows"]]
    return data


def report(paths: list[str]) -> str:
    data = joined(paths)
    s = summarize(data)
    lines = [f"{data['task']}, {data['gpus']} processes ({data['device_name']}), {data['date']}: one node of "
             f"{data['gpus']} against {data['nodes']} nodes of {data['gpus'] // data['nodes']}", "",
             "| repeat | layout | exit codes | iterations | samples/s |", "|---:|---|---|---:|---:|"]
    for r in data["rows"]:
        speed = "-" if r["samples_per_s"] is None else f"{r['samples_per_s'] / 1e6:.3f} M"
        layout = "1 node" if r["nodes"] == 1 else f"{r['nodes']} nodes"
        lines.append(f"| {r['repeat']} | {layout} | {' '.join(map(str, r['exit_codes']))} | {r['iterations']} | {speed} |")
    if s["median_ratio"] is None:
        lines += ["", "No repeat has both layouts' speeds: nothing to compare."]
    else:
        lines += ["", f"{data['nodes']} nodes / 1 node: {s['median_ratio']:.3f} (median of {len(s['ratios'])}: "
                  f"{', '.join(f'{x:.3f}' for x in s['ratios'])}); target within {WITHIN:.0%}: "
                  f"{'met' if s['holds'] else 'not met'}"]
    return "\n".join(lines)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", help="directory for nodes.json and the runs")
    ap.add_argument("--report", nargs="+", metavar="NODES_JSON", help="print the table of earlier runs (joined) and stop")
    ap.add_argument("--task", default="Ant")
    ap.add_argument("--gpus", type=int, default=4, help="processes in all, one per GPU (default 4)")
    ap.add_argument("--nodes", type=int, default=2, help="torchrun agents to split them over (default 2)")
    ap.add_argument("--seconds", type=float, default=60.0, help="--time-limit of each run (default 60)")
    ap.add_argument("--repeats", type=int, default=3, help="runs of each layout (default 3)")
    ap.add_argument("--num-envs", type=int, default=None, help="default: train's, per process")
    ap.add_argument("--device", default=None, help="cpu to check the script on a machine without GPUs")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if reported(ap, args, report, "NODES_JSON"):
        return 0
    if args.nodes < 2 or args.gpus % args.nodes:
        ap.error(f"--gpus {args.gpus} --nodes {args.nodes}: need at least 2 nodes and a whole number of GPUs "
                 f"on each, e.g. --gpus 4 --nodes 2")
    if args.repeats < 1 or args.seconds <= 0:
        ap.error(f"--repeats {args.repeats} --seconds {args.seconds}: need at least one repeat of some seconds")
    import torch  # noqa: PLC0415

    cuda = args.device in (None, "cuda") or str(args.device).startswith("cuda")
    if cuda and torch.cuda.device_count() < args.gpus:
        raise SystemExit(f"--gpus {args.gpus}: this machine has {torch.cuda.device_count()} GPUs; ask for fewer, "
                         "or pass --device cpu to check the script")
    os.makedirs(os.path.join(args.out, "runs"), exist_ok=True)
    data = {"argv": sys.argv[1:] if argv is None else argv, "task": args.task, "gpus": args.gpus,
            "nodes": args.nodes, "seconds": args.seconds, "date": time.strftime("%Y-%m-%d"),
            "device_name": torch.cuda.get_device_name(0) if cuda else "CPU", "rows": []}
    for k in range(args.repeats):
        for nodes in ((1, args.nodes) if k % 2 == 0 else (args.nodes, 1)):
            row = dict(run_layout(args, f"r{k}-{nodes}node", nodes), repeat=k)
            data["rows"].append(row)
            data["summary"] = summarize(data)
            print(json.dumps(row), flush=True)
            write_json(os.path.join(args.out, "nodes.json"), data)
    print(report([os.path.join(args.out, "nodes.json")]))
    return 0 if all(c == 0 for r in data["rows"] for c in r["exit_codes"]) else 1


if __name__ == "__main__":
    sys.exit(main())
