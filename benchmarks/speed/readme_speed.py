"""The README's speed table ("Results at a glance") from the committed JSON of the runs it quotes, one measure a
column: each task's env stepped with random actions, in env-steps per second, at the number of envs and on the GPU
of that run, and beside it what the peer ran on the same host (EnvPool on the host's cores for Gymnasium's tasks,
mjlab 1.6's env at the same number of envs for the legged tasks: the range over every committed side by side).

    python -m benchmarks.speed.readme_speed        # benchmarks/doc_tables.py writes it into README.md
"""

from __future__ import annotations

import glob
import json
import os

from benchmarks.harness import ROOT

BENCH = os.path.join(ROOT, "docs", "bench")
# id, policy observation / actions, where its figure comes from: ("robot", JSON, envs), ("suite", task, envs) or
# ("legged", task, envs)
ROWS = [
    ("warpgym/Ant-v0", "60 / 8", ("robot", "envs_per_gpu/h100_envs_per_gpu_ant_throughput.json", 4096)),
    ("warpgym/Humanoid-v0", "108 / 21", ("robot", "envs_per_gpu/h100_envs_per_gpu_humanoid_throughput.json", 4096)),
    ("warpgym/Hopper-v5", "11 / 3", ("suite", "Hopper-v5", 32768)),
    ("warpgym/Humanoid-v5", "348 / 17", ("suite", "Humanoid-v5", 32768)),
    ("warpgym/Go1VelocityFlat-v0", "48 (critic 72) / 12", ("legged", "Go1VelocityFlat-v0", 4096)),
    ("warpgym/G1VelocityFlat-v0", "99 (critic 111) / 29", ("legged", "G1VelocityFlat-v0", 4096)),
    ("warpgym/Go1VelocityRough-v0", "235 (critic 259) / 12", ("legged", "Go1VelocityRough-v0", 4096)),
    ("warpgym/G1VelocityRough-v0", "286 (critic 298) / 29", ("legged", "G1VelocityRough-v0", 4096)),
]
SUITE_GPU = "suite_speed_h100_same_states.json"  # warpgym's steps of the suite on the GPU
SUITE_CPU = "suite_speed_h100_cpu.json"  # EnvPool's on the same host's cores


def load(name: str) -> dict:
    with open(os.path.join(BENCH, name)) as f:
        return json.load(f)


def short(gpu: str) -> str:
    """"NVIDIA H100 80GB HBM3" -> "H100"."""
    return next((w for w in gpu.split() if w[:1] in "ABHL" and w[1:].isdigit()), gpu)


def robot_row(path: str, envs: int) -> tuple[float, str, str]:
    doc = load(path)
    rate = next(r["env_steps_per_s"] for r in doc["throughput"] if r["num_envs"] == envs)
    return rate, short(doc["device"]), "-"


def suite_row(task: str, envs: int) -> tuple[float, str, str]:
    gpu, cpu = load(SUITE_GPU), load(SUITE_CPU)
    rate = next(r["env_steps_per_s"] for r in gpu["gpu"] if r["task"] == task and r["num_envs"] == envs)
    envpool = cpu["cpu"][task]["envpool"]["steps_per_s"]
    return rate, short(gpu["meta"]["gpu"]), f"{rate / envpool:.0f}x EnvPool on {cpu['meta']['cpu_cores']} cores"


def legged_row(task: str, envs: int) -> tuple[float, str, str]:
    """The latest side by side's rate; the ratio to mjlab's env over every side by side of the task at ``envs``."""
    runs = []
    for path in sorted(glob.glob(os.path.join(BENCH, "legged", "side_by_side_*.json"))):
        with open(path) as f:
            summary = json.load(f)
        rows = {r["framework"]: r["env_steps_per_s"] for r in summary["tasks"].get(task, {}).get("speed", [])
                if r["num_envs"] == envs}
        if len(rows) == 2:
            runs.append((summary["date"], rows["warpgym"], rows["warpgym"] / rows["mjlab"], summary["device"]))
    if not runs:
        raise SystemExit(f"no side by side of {task} at {envs} envs under docs/bench/legged")
    date, rate, _, device = max(runs)
    low, high = min(r[2] for r in runs), max(r[2] for r in runs)
    ratio = f"{low:.1f}x" if f"{low:.1f}" == f"{high:.1f}" else f"{low:.1f}-{high:.1f}x"
    return rate, short(device), f"{ratio} mjlab 1.6's env"


def table() -> str:
    lines = ["| task | obs / actions | env-steps/s, random actions | envs, GPU | against the peer, same host |",
             "|---|---|---|---|---|"]
    for name, widths, (kind, what, envs) in ROWS:
        rate, gpu, peer = {"robot": robot_row, "suite": suite_row, "legged": legged_row}[kind](what, envs)
        lines.append(f"| `{name}` | {widths} | {rate / 1e6:.2f} M | {envs}, {gpu} | {peer} |")
    return "\n".join(lines)


def main(argv=None) -> int:
    print(table())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
