"""The one-way layering (docs/DESIGN and README, "Layout"): scripts and the command on top, the
environment (warpgym -> kernels) and the learner (agents) side by side below, no import running back up.
agents' own rule is tested in test_agents.py."""

import ast
import os
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
    allowed = {"warp", "kernels", "__future__", "math"}
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
