"""The one-way layering (README, "Layout"): scripts and the command on top, the environment (warpgym ->
kernels) and the learner (agents) side by side below, no import running back up; one registry of tasks.
agents' own rule is tested in test_agents.py."""

import ast
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def imports_of(package: str):
    """(file, imported top-level name) for every import statement under ``package``."""
    for folder, _, files in os.walk(os.path.join(ROOT, package)):
        for name in files:
            if name.endswith(".py"):
                path = os.path.join(folder, name)
                for node in ast.walk(ast.parse(open(path).read())):
                    if isinstance(node, ast.Import):
                        mods = [a.name for a in node.names]
                    elif isinstance(node, ast.ImportFrom) and node.level == 0:
                        mods = [node.module or ""]
                    else:
                        continue
                    for m in mods:
                        yield os.path.relpath(path, ROOT), m


def test_only_the_command_imports_the_learner():
    users = sorted({f for f, m in imports_of("warpgym") if m.split(".")[0] == "agents"})
    assert users and all(f.startswith(os.path.join("warpgym", "cli") + os.sep) for f in users), users


def test_kernels_import_warp_and_each_other_only():
    allowed = {"warp", "kernels", "__future__", "math", "enum"}
    wrong = sorted({(f, m) for f, m in imports_of("kernels") if m.split(".")[0] not in allowed})
    assert not wrong, wrong


def test_importing_warpgym_loads_no_learner_and_no_command():
    code = "import sys, warpgym; print(sorted(m for m in sys.modules if m.split('.')[0] == 'agents' or m.startswith('warpgym.cli')))"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert done.stdout.strip() == "[]", done.stdout


def test_the_wheel_lists_every_package():
    """pyproject.toml names its packages one by one: a new sub-package missing there installs from a
    checkout (editable) and is absent from the wheel."""
    import tomllib

    listed = set(tomllib.load(open(os.path.join(ROOT, "pyproject.toml"), "rb"))["tool"]["setuptools"]["packages"])
    found = set()
    for top in ("warpgym", "kernels", "agents"):
        for folder, _, files in os.walk(os.path.join(ROOT, top)):
            if "__init__.py" in files and "__pycache__" not in folder:
                found.add(os.path.relpath(folder, ROOT).replace(os.sep, "."))
    assert found == listed, (sorted(found - listed), sorted(listed - found))


def test_only_the_registry_asks_which_family_a_task_belongs_to():
    """warpgym.tasks.registry is the one place that tells warpgym's robots from Gymnasium's suite: a test of
    membership in the suite's table anywhere else is a second registry growing."""
    asks = re.compile(r"\bin\s+SUITE\b(?!\.)")  # SUITE.items() is a walk over the suite, not a question
    own = {os.path.join("warpgym", "tasks", "registry.py"), os.path.join("warpgym", "tasks", "suite", "__init__.py")}
    found = []
    for top in ("warpgym", "agents", "kernels", "benchmarks", "scripts"):
        for folder, _, files in os.walk(os.path.join(ROOT, top)):
            for name in files:
                path = os.path.join(folder, name)
                rel = os.path.relpath(path, ROOT)
                if name.endswith(".py") and rel not in own:
                    found += [f"{rel}:{i}" for i, line in enumerate(open(path), 1) if asks.search(line)]
    assert not found, found


def test_warpgym_imports_run_one_way_down_its_layers():
    """CONTRIBUTING.md's order, at module level: cli -> envs -> media -> native -> tasks -> sim; a module imports
    nothing of a layer above its own when it is imported (a function that builds something of a layer above, as the
    registry's contract does, imports it when it is called)."""
    order = ["cli", "envs", "media", "native", "tasks", "sim"]

    def layer(module: str):
        parts = module.split(".")
        if parts[0] != "warpgym" or len(parts) == 1:
            return None
        return parts[1]

    upward = []
    for folder, _, files in os.walk(os.path.join(ROOT, "warpgym")):
        for name in files:
            if not name.endswith(".py"):
                continue
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, ROOT)
            mine = layer(rel[:-3].replace(os.sep, "."))
            for node in ast.parse(open(path).read()).body:
                if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                    mods = [node.module]
                elif isinstance(node, ast.Import):
                    mods = [a.name for a in node.names]
                else:
                    continue
                for m in mods:
                    theirs = layer(m)
                    if mine in order and theirs in order and order.index(theirs) < order.index(mine):
                        upward.append(f"{rel} imports {m}")
    assert not upward, upward


def test_no_module_asks_which_family_a_task_is_by_name():
    """A command reaches what differs by family through the task's registry entry (its callables and flags), never
    by comparing the family's or the judge's name (``entry.family == "legged"``)."""
    asks = re.compile(r"\.family\s*[!=]=|\.scored_in\s*[!=]=|\bfamily\s*[!=]=\s*[\"']|[\"'](robots|suite|legged)[\"']\s*[!=]=")
    own = os.path.join("warpgym", "tasks", "registry.py")
    found = []
    for top in ("warpgym", "agents", "kernels", "benchmarks", "scripts"):
        for folder, _, files in os.walk(os.path.join(ROOT, top)):
            for name in files:
                rel = os.path.relpath(os.path.join(folder, name), ROOT)
                if name.endswith(".py") and rel != own:
                    found += [f"{rel}:{i}" for i, line in enumerate(open(os.path.join(ROOT, rel)), 1) if asks.search(line)]
    assert not found, found


def test_every_task_of_the_registry_is_a_gymnasium_id_with_its_entry_points():
    import gymnasium as gym

    import warpgym  # noqa: F401  (registers the ids)
    from warpgym.tasks.registry import REGISTRY, task_entry, task_names

    assert task_names("robots") == ["Ant", "Humanoid"] and len(task_names("suite")) == 11
    for name, entry in REGISTRY.items():
        spec = gym.spec(entry.gym_id)
        assert (spec.entry_point, spec.vector_entry_point) == (entry.single_entry_point, entry.vector_entry_point)
        assert spec.max_episode_steps == entry.episode_length and spec.kwargs["task"] == name
        assert task_entry(name.lower()) is entry


def test_benchmarks_are_a_package_in_folders_by_what_they_measure_and_edit_no_import_path():
    """Each harness sits in the folder of what it measures and runs as ``python -m benchmarks.GROUP.NAME``: no
    script reaches for its neighbours through sys.path."""
    groups = {"speed", "learning", "multi_gpu", "physics", "reliability"}
    top = os.path.join(ROOT, "benchmarks")
    loose = sorted(n for n in os.listdir(top) if n.endswith(".py"))
    # beside the groups only what serves them all: the shared harness, the targets, the docs' table writer
    assert loose == ["__init__.py", "doc_tables.py", "harness.py", "targets.py"], loose
    folders = {n for n in os.listdir(top) if os.path.isdir(os.path.join(top, n)) and n != "__pycache__"}
    assert folders == groups, folders
    for group in groups:
        assert os.path.isfile(os.path.join(top, group, "__init__.py")), group
    edits = []
    for folder, _, files in os.walk(top):
        for name in files:
            if name.endswith(".py"):
                text = open(os.path.join(folder, name)).read()
                edits += [os.path.relpath(os.path.join(folder, name), ROOT)] if "sys.path" in text else []
    assert not edits, edits


def test_each_family_has_a_module_named_for_it_in_every_layer():
    """A family's own code sits where its name says, layer by layer (CONTRIBUTING.md, "Where things go"): its task
    definitions in tasks/F/, its kernels in kernels/F/, its vector and single envs in envs/F.py, its frames and clips
    in media/F.py, its judge outside warpgym in native/F.py, its `warpgym bench` and `warpgym eval` in
    cli/bench/F.py and cli/eval/F.py; and its registry entry's commands call into those modules."""
    from warpgym.tasks.registry import REGISTRY

    families = {e.family for e in REGISTRY.values()}
    assert families == {"robots", "suite", "legged"}, families
    for f in sorted(families):
        for path in (f"warpgym/tasks/{f}/__init__.py", f"kernels/{f}/__init__.py", f"warpgym/envs/{f}.py",
                     f"warpgym/media/{f}.py", f"warpgym/native/{f}.py", f"warpgym/cli/bench/{f}.py", f"warpgym/cli/eval/{f}.py"):
            assert os.path.isfile(os.path.join(ROOT, path)), path
    for name, e in REGISTRY.items():
        f = e.family
        assert e.vector_entry_point.startswith(f"warpgym.envs.{f}:"), (name, e.vector_entry_point)
        assert e.single_entry_point.startswith(f"warpgym.envs.{f}:"), (name, e.single_entry_point)
        assert e.draw_clip.__name__.startswith(f"warpgym.media.{f}."), (name, e.draw_clip.__name__)
        assert e.evaluate.__name__.startswith(f"warpgym.cli.eval.{f}."), (name, e.evaluate.__name__)
        assert e.bench.__name__.startswith(f"warpgym.cli.bench.{f}."), (name, e.bench.__name__)


def test_what_the_families_share_imports_no_family():
    """The modules every family builds on (the single env, the GL context and frame checks, the video writer, the
    vector env's graph) name no family: a family's code there would be a second place for it."""
    from warpgym.tasks.registry import REGISTRY

    families = {e.family for e in REGISTRY.values()}
    shared = ("warpgym/envs/single.py", "warpgym/envs/graph_env.py", "warpgym/media/render.py", "warpgym/media/video.py")
    found = []
    for rel in shared:
        for node in ast.walk(ast.parse(open(os.path.join(ROOT, rel)).read())):
            if isinstance(node, ast.ImportFrom) and node.module:
                mods = [node.module]
            elif isinstance(node, ast.Import):
                mods = [a.name for a in node.names]
            else:
                continue
            found += [f"{rel} imports {m}" for m in mods if families & set(m.split(".")[1:])]
    assert not found, found


def test_kernels_are_laid_out_by_family():
    """What both families use is in kernels/common.py; the robots' kernels in kernels/robots/, the suite's in
    kernels/suite/; what stays at the top serves the simulator (the Tensor API's layout, solver load, math)."""
    top = os.path.join(ROOT, "kernels")
    assert sorted(n for n in os.listdir(top) if n.endswith(".py")) == [
        "__init__.py", "common.py", "math.py", "solver_load.py", "tensor_api.py"]
    for family in ("robots", "suite"):
        assert os.path.isfile(os.path.join(top, family, "__init__.py")), family
        assert os.path.isfile(os.path.join(top, family, "step.py")) and os.path.isfile(os.path.join(top, family, "resets.py"))
    # the families import what they share from common and nothing from each other
    crossing = [(f, m) for f, m in imports_of("kernels")
                if (f.startswith(os.path.join("kernels", "robots")) and m.startswith("kernels.suite"))
                or (f.startswith(os.path.join("kernels", "suite")) and m.startswith("kernels.robots"))]
    assert not crossing, crossing
