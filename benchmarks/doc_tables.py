"""The docs' generated tables: each lies between two markers on its page and is what a benchmark's ``--report``
prints from the committed JSON, word for word.

    python -m benchmarks.doc_tables --check        # exit 1 and show the difference where a page and its JSON part
    python -m benchmarks.doc_tables --write        # rewrite every block from its JSON

A block on a page:

    <!-- table: NAME -->
    ...what BLOCKS[NAME] prints...
    <!-- end table -->

Each entry of BLOCKS names its page, the report's command (a module and its arguments, run in this process) and
which of the printed paragraphs (the output split at blank lines) make the block; the command is written above
the block on the page, so a reader can run it.
"""

from __future__ import annotations

import argparse
import contextlib
import difflib
import importlib
import io
import os
import re
import sys

from benchmarks.harness import ROOT

FIDELITY = [f"docs/bench/fidelity/{r}.json" for r in (
    "h100_ant_seed0_600s", "h100_ant_seed1_600s", "h100_ant_8192envs_seed0_300s",
    "h100_humanoid_3x8_motor25_armature0.1_seed0_600s", "h100_humanoid_3x8_motor25_armature0.1_seed1_600s")]
RLLIB = [f"docs/bench/rllib/h200_rllib_{r}.json" for r in (
    "vs_warpgym_1gpu", "8runners_1gpu", "vs_warpgym_2gpu_warpgym", "vs_warpgym_2gpu_rllib", "vs_warpgym_2gpu_rllib_humanoid",
    "vs_warpgym_4gpu_ant", "vs_warpgym_4gpu_humanoid")]
LEGGED = [f"docs/bench/legged/side_by_side_{r}.json" for r in (
    "go1_15min_2026-11-28", "g1_15min_2026-11-29", "go1_rough_9min_2026-11-29", "g1_rough_15min_2026-11-29",
    "g1_rough_15min_seed1_2026-11-29")]
BEFORE_AFTER = [f"docs/bench/speed/before_after_{r}_2026-12-02.json" for r in ("legged_flat", "legged_rough",
                                                                                "suite_robots")]
ENVS_ANT = ["--report", "docs/bench/envs_per_gpu/h100_envs_per_gpu_ant.json", "--figure", "-"]
ENVS_HUMANOID = ["--report", "docs/bench/envs_per_gpu/h100_envs_per_gpu_humanoid_seed0.json",
                 "docs/bench/envs_per_gpu/h100_envs_per_gpu_humanoid_seed1.json", "--figure", "-"]
SUITE_LEARNING = ["--report", "docs/bench/suite_learning", "docs/bench/suite_sb3"]


def after(marker: str, count: int):
    """The ``count`` paragraphs after the one that is ``marker``."""
    def pick(paragraphs: list[str]) -> list[str]:
        i = paragraphs.index(marker)
        return paragraphs[i + 1 : i + 1 + count]
    return pick


def first(count: int, start: int = 0):
    return lambda paragraphs: paragraphs[start : start + count]


def only(*indices: int):
    """The printed paragraphs at ``indices``: a page shows part of a report, the log the rest."""
    return lambda paragraphs: [paragraphs[i] for i in indices]


def last(count: int):
    return lambda paragraphs: paragraphs[-count:]


def scaling(folder: str, task: str) -> tuple:
    return ("docs/benchmarks.md", "benchmarks.multi_gpu.scaling", ["--report", f"docs/bench/multi_gpu/{folder}", "--task", task],
            first(2))


# name: (page, module, arguments, the paragraphs of its output that make the block)
BLOCKS = {
    "readme-speed": ("README.md", "benchmarks.speed.readme_speed", [], first(1)),
    "readme-learning": ("README.md", "benchmarks.learning.suite_learning", SUITE_LEARNING,
                        after("The README's table:", 2)),
    "suite-learning": ("docs/benchmarks.md", "benchmarks.learning.suite_learning", SUITE_LEARNING, first(2)),
    "suite-sb3": ("docs/benchmarks.md", "benchmarks.learning.suite_learning", ["--report", "docs/bench/suite_sb3"],
                  first(1)),
    "suite-speed": ("docs/benchmarks.md", "benchmarks.speed.suite_speed",
                    ["--report", "docs/bench/suite_speed_h100_same_states.json", "docs/bench/suite_speed_h100_cpu.json"],
                    first(1)),
    "legged": ("docs/benchmarks.md", "benchmarks.learning.mjlab_side_by_side", ["--report", *LEGGED], first(3)),
    "before-after": ("docs/benchmarks.md", "benchmarks.speed.before_after", ["--report", *BEFORE_AFTER], first(1)),
    "before-after-events": ("docs/history.md", "benchmarks.speed.before_after",
                            ["--report", *(f"docs/bench/speed/before_after_events_{r}_2026-12-03.json"
                                           for r in ("flat", "rough"))], first(1)),
    "before-after-events-rest": ("docs/history.md", "benchmarks.speed.before_after",
                                 ["--report", *(f"docs/bench/speed/before_after_events_{r}_2026-12-03.json"
                                                for r in ("g1_rough", "suite_robots"))], first(1)),
    "before-after-own-terms": ("docs/history.md", "benchmarks.speed.before_after",
                               ["--report", "docs/bench/speed/before_after_own_terms_2026-12-03.json"], first(1)),
    "train-modes-hopper": ("docs/history.md", "benchmarks.speed.train_modes",
                           ["--report", "docs/bench/speed/train_modes_hopper_h200_2026-12-03.json"], first(2)),
    "legged-terms": ("docs/tasks.md", "warpgym.tasks.term_tables", [], first(4)),
    "legged-7min": ("docs/history.md", "benchmarks.learning.mjlab_side_by_side",
                    ["--report", "docs/bench/legged/side_by_side_2026-11-28.json"], first(3)),
    # the page: each policy's speeds in both simulators; the log: its training run
    "physics": ("docs/benchmarks.md", "benchmarks.physics.fidelity", ["--report", *FIDELITY, "--marks", "end"],
                first(1)),
    "physics-training": ("docs/history.md", "benchmarks.physics.fidelity", ["--report", *FIDELITY, "--marks", "end"],
                         only(1)),
    "robot-steps": ("docs/benchmarks.md", "benchmarks.speed.robot_steps",
                    ["--report", "docs/bench/h100_env_steps_humanoid_motors.json"], first(2)),
    "cold-start": ("docs/benchmarks.md", "benchmarks.speed.cold_start",
                   ["--report", "docs/bench/cold_start/h100_cold_start_humanoid_motors.json"], first(2)),
    "learners-ant": ("docs/benchmarks.md", "benchmarks.learning.learners",
                     ["--report", "docs/bench/learners/h100_learners_ant.json"], first(2)),
    "learners-humanoid": ("docs/history.md", "benchmarks.learning.learners",
                          ["--report", "docs/bench/learners/h100_learners_humanoid.json"], first(2)),
    # the page: each size's time to the speeds; the log: each size's throughput and memory
    "envs-per-gpu-ant": ("docs/benchmarks.md", "benchmarks.speed.envs_per_gpu", ENVS_ANT, only(0, 2)),
    "envs-per-gpu-humanoid": ("docs/history.md", "benchmarks.speed.envs_per_gpu", ENVS_HUMANOID, only(0, 2)),
    "envs-per-gpu-ant-throughput": ("docs/history.md", "benchmarks.speed.envs_per_gpu", ENVS_ANT, only(0, 1)),
    "envs-per-gpu-humanoid-throughput": ("docs/history.md", "benchmarks.speed.envs_per_gpu", ENVS_HUMANOID, only(0, 1)),
    "rllib": ("docs/benchmarks.md", "benchmarks.learning.learners", ["--report", *RLLIB], first(2)),
    "robot-zoo": ("docs/benchmarks.md", "benchmarks.learning.robot_zoo",
                  ["table", *(f"docs/bench/robot_zoo/robot_zoo_2026-12-03_{n}.json" for n in ("three", "two", "four")),
                   "docs/bench/robot_zoo/robot_zoo_2026-12-04_gifs.json"],
                  first(1)),
    "off-policy-gate": ("docs/benchmarks.md", "benchmarks.learning.robot_zoo",
                        ["table", "docs/bench/off_policy/go1_gate_2026-12-04.json"], first(1)),
    "scaling-ant": scaling("grow_kl", "Ant"),
    "scaling-humanoid": scaling("grow_kl", "Humanoid"),
    "scaling-humanoid-v5": scaling("suite", "Humanoid-v5"),
    "scaling-ant-v5": scaling("suite", "Ant-v5"),
    "scaling-g1-flat": scaling("legged", "G1VelocityFlat-v0"),
    "scaling-go1-rough": scaling("legged", "Go1VelocityRough-v0"),
    "rough-settings-contacts": ("docs/history.md", "benchmarks.physics.rough_settings",
                                ["--report", "docs/bench/legged/rough_settings_Go1VelocityRough-v0_2026-11-29.json"], first(2)),
    "rough-settings-ground": ("docs/history.md", "benchmarks.physics.rough_settings",
                              ["--report", "docs/bench/legged/rough_settings_heightfields_2026-11-29.json"], first(2)),
    # the table only: the compile times under it differ from run to run
    "ground-resampling": ("docs/history.md", "benchmarks.physics.ground_resampling", [], first(1)),
    "nodes": ("docs/history.md", "benchmarks.multi_gpu.nodes", ["--report", "docs/bench/multi_gpu/nodes/nodes-4.json"],
              first(3)),
    "exits-cpu": ("docs/history.md", "benchmarks.reliability.exits", ["--report", "docs/bench/cpu_exits.json"],
                  lambda paragraphs: ["```\n" + paragraphs[-1] + "\n```"]),
    "exits-gpu": ("docs/benchmarks.md", "benchmarks.reliability.exits",
                  ["--report", "docs/bench/gpu_exits.json", "docs/bench/reliability/gpu_exits_h200.json",
                   "docs/bench/reliability/gpu_exits_h200x4_a.json", "docs/bench/reliability/gpu_exits_h200x4_b.json"],
                  lambda paragraphs: ["```\n" + paragraphs[-1] + "\n```"]),
}

BLOCK = re.compile(r"<!-- table: (?P<name>[\w-]+) -->\n(?P<body>.*?)<!-- end table -->", re.S)


def printed(module: str, args: list[str]) -> str:
    """What ``python -m module args`` prints, run here from the repository's root."""
    out = io.StringIO()
    cwd = os.getcwd()
    try:
        os.chdir(ROOT)
        with contextlib.redirect_stdout(out):
            code = importlib.import_module(module).main(list(args))
    finally:
        os.chdir(cwd)
    if code not in (0, None):
        raise SystemExit(f"python -m {module} {' '.join(args)} exited {code}")
    return out.getvalue()


def generate(name: str) -> str:
    _, module, args, pick = BLOCKS[name]
    paragraphs = [p.strip("\n") for p in re.split(r"\n\s*\n", printed(module, args)) if p.strip()]
    return "\n\n".join(pick(paragraphs)) + "\n"


def blocks_on(page: str) -> dict[str, str]:
    with open(os.path.join(ROOT, page)) as f:
        return {m["name"]: m["body"] for m in BLOCK.finditer(f.read())}


def check() -> list[str]:
    """One message for each block whose page and report part, and for each marker without a registered block."""
    problems = []
    pages = sorted({page for page, *_ in BLOCKS.values()})
    found = {}
    for page in pages:
        for name, body in blocks_on(page).items():
            found[name] = page
            if name not in BLOCKS:
                problems.append(f"{page}: a block named {name!r} that benchmarks/doc_tables.py does not know")
                continue
            want = generate(name)
            if body != want:
                diff = "".join(difflib.unified_diff(body.splitlines(True), want.splitlines(True), "page", "report"))
                problems.append(f"{page}: block {name!r} differs from its report "
                                f"(python -m benchmarks.doc_tables --write rewrites it):\n{diff}")
    for name, (page, *_) in BLOCKS.items():
        if found.get(name) != page:
            problems.append(f"{page}: no block {name!r} (add its markers where the table belongs)")
    return problems


def write() -> None:
    for page in sorted({page for page, *_ in BLOCKS.values()}):
        path = os.path.join(ROOT, page)
        with open(path) as f:
            text = f.read()
        new = BLOCK.sub(lambda m: f"<!-- table: {m['name']} -->\n{generate(m['name'])}<!-- end table -->"
                        if m["name"] in BLOCKS else m.group(0), text)
        if new != text:
            with open(path, "w") as f:
                f.write(new)
            print(f"rewrote {page}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    mode = ap.add_mutually_exclusive_group(required=True)
    mode.add_argument("--check", action="store_true", help="compare every block with its report")
    mode.add_argument("--write", action="store_true", help="rewrite every block from its report")
    args = ap.parse_args(argv)
    if args.write:
        write()
        return 0
    problems = check()
    for p in problems:
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
