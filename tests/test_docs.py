"""The docs say only what is true of the code: every path, module, command flag and link they name exists, the
generated CLI reference matches the parsers, and their Python examples run (on the CPU, at a few envs)."""

import os
import re
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The reference pages and the README. The lab log (docs/history.md) records paths and flags of its day and is
# read as history; docs/benchmarks.md is checked for links only until its rewrite (its commands name flags of
# the scripts of each row's day).
PAGES = ["README.md", "CONTRIBUTING.md", "docs/guide.md", "docs/tasks.md", "docs/tensor_api.md", "docs/cli.md"]
ALL_PAGES = PAGES + ["docs/benchmarks.md", "docs/history.md"]
TOPS = ("warpgym", "agents", "kernels", "benchmarks", "scripts", "tests", "docs", ".ci", "shared")
PATH = re.compile(r"(?<![\w/.$~-])((?:%s)/[\w./*-]*[\w*])" % "|".join(re.escape(t) for t in TOPS))
PLACEHOLDER = re.compile(r"[A-Z]{2,}|<|\*|\.\.\.")  # RUN, OUT, <task>, globs: not a path of the repository
MODULE = re.compile(r"python -m ((?:warpgym|benchmarks|agents)(?:\.\w+)*)")
COMMAND = re.compile(r"\bwarpgym (train-with|train|play|plot|sim2sim|bench|eval)\b([^`|;&\n]*)")
SCRIPT_FLAGS = re.compile(r"python -m ((?:benchmarks)(?:\.\w+)+)([^`|;&\n]*)")
FLAG = re.compile(r"(?<![\w-])(--[a-z][\w-]*)")
LINK = re.compile(r"\[[^\]]*\]\(([^)\s]+)\)|<img src=\"([^\"]+)\"")


def read(page: str) -> str:
    with open(os.path.join(ROOT, page)) as f:
        return f.read()


def module_exists(name: str) -> bool:
    path = os.path.join(ROOT, *name.split("."))
    return os.path.isfile(path + ".py") or os.path.isfile(os.path.join(path, "__init__.py"))


def slug(heading: str) -> str:
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


@pytest.mark.parametrize("page", PAGES)
def test_every_path_and_module_a_page_names_exists(page):
    text = read(page)
    # warpgym/Hopper-v5 and the like are Gymnasium ids, not paths
    missing = sorted({p for p in PATH.findall(text) if not PLACEHOLDER.search(p) and not re.match(r"warpgym/[A-Z]", p)
                      and not os.path.exists(os.path.join(ROOT, p.rstrip(".")))})
    missing += sorted({m for m in MODULE.findall(text) if not PLACEHOLDER.search(m) and not module_exists(m)})
    assert not missing, f"{page} names what is not in the repository: {missing}"


@pytest.fixture(scope="module")
def command_flags():
    from warpgym.cli.reference import command_parser

    flags = {}
    for name in ("train", "train-with", "play", "plot", "sim2sim", "bench", "eval"):
        parser = command_parser(name)
        flags[name] = {s for a in parser._actions for s in a.option_strings}
    return flags


@pytest.mark.parametrize("page", PAGES)
def test_every_flag_of_a_command_a_page_shows_is_one_the_command_takes(page, command_flags):
    text = read(page)
    wrong = []
    for name, rest in COMMAND.findall(text):
        wrong += [f"warpgym {name} {f}" for f in FLAG.findall(rest) if f not in command_flags[name]]
    for module, rest in SCRIPT_FLAGS.findall(text):
        if not module_exists(module):
            continue  # the path test names it
        source = read(os.path.join(*module.split(".")) + ".py")
        wrong += [f"python -m {module} {f}" for f in FLAG.findall(rest) if f'"{f}"' not in source]
    assert not wrong, f"{page} shows flags its commands do not take: {sorted(set(wrong))}"


@pytest.mark.parametrize("page", ALL_PAGES)
def test_every_relative_link_and_image_of_a_page_resolves_with_its_anchor(page):
    text = read(page)
    broken = []
    for target in (a or b for a, b in LINK.findall(text)):
        if re.match(r"[a-z]+:", target):
            continue  # an address outside the repository
        path, _, anchor = target.partition("#")
        file = os.path.normpath(os.path.join(ROOT, os.path.dirname(page), path)) if path else os.path.join(ROOT, page)
        if not os.path.exists(file):
            broken.append(target)
        elif anchor and file.endswith(".md"):
            with open(file) as f:
                anchors = {slug(line.lstrip("#")) for line in f if line.startswith("#")}
            if anchor not in anchors:
                broken.append(target)
    assert not broken, f"{page} links to what is not there: {broken}"


def test_the_cli_reference_is_what_the_parsers_say():
    from warpgym.cli.reference import render

    assert read("docs/cli.md") == render(), "docs/cli.md is stale: python -m warpgym.cli.reference docs/cli.md"


def python_blocks(page: str) -> list[str]:
    return re.findall(r"```python\n(.*?)```", read(page), re.S)


def run_on_the_cpu(code: str, tmp_path) -> None:
    """``code`` as a reader would paste it, moved to the CPU at a few envs."""
    code = code.replace('"cuda:0"', '"cpu"').replace("8192", "4").replace("4096", "4").replace("1024", "4")
    script = tmp_path / "example.py"
    script.write_text(code)
    done = subprocess.run([sys.executable, str(script)], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, code + "\n" + done.stderr[-3000:]


def test_the_readmes_python_example_runs(tmp_path):
    blocks = python_blocks("README.md")
    assert len(blocks) == 1
    run_on_the_cpu(blocks[0], tmp_path)


def test_the_guides_own_terms_example_runs_and_reads_the_robots_feet(tmp_path):
    """docs/guide.md's term of one's own: the Go1 at its keyframe stands with its front feet 0.2 m apart, so a
    minimum of 0.15 m costs nothing; the observation grows by the one entry."""
    block = next(b for b in python_blocks("docs/guide.md") if "feet_apart" in b)
    run_on_the_cpu(block + "\nassert obs.shape == (4, 49) and float(info['reward_feet_apart'].abs().max()) == 0.0\n"
                   "assert torch.allclose(obs[:, -1], envs.sim.to_torch(envs.sim.d.xpos)[:, envs.index.root_body, 2],"
                   " atol=0.05)\n", tmp_path)


def test_the_guides_suite_terms_example_adds_its_term_to_gymnasiums_reward(tmp_path):
    """docs/guide.md's reward and termination of one's own on Hopper-v5: the reward is Gymnasium's terms plus the
    user's, which is the torso's angle squared at its weight."""
    block = next(b for b in python_blocks("docs/guide.md") if "torso_tilt" in b)
    run_on_the_cpu(block + "\nangle = envs.sim.dof_pos[:, 2]\n"
                   "assert torch.allclose(info['reward_tilt'], -0.5 * angle * angle, atol=1e-7)\n"
                   "own = info['reward_forward'] + info['reward_ctrl'] + info['reward_survive'] + info['reward_tilt']\n"
                   "assert torch.allclose(reward, own, atol=1e-6) and float(angle.abs().max()) > 0\n", tmp_path)


def test_the_tensor_api_pages_first_example_runs_with_the_tasks_physics(tmp_path):
    block = python_blocks("docs/tensor_api.md")[0]
    assert "substeps=ANT.substeps" in block
    run_on_the_cpu(block + "\nassert sim.substeps == 4 and sim.physics.armature == 0.1\n", tmp_path)


def test_the_logs_table_of_moved_paths_points_at_paths_that_exist():
    """docs/history.md keeps the paths of each entry's day; its table says where each went, and that must hold."""
    text = read("docs/history.md")
    table = text[text.index("| named here | now |"):].split("\n\n")[0]
    now = [p for row in table.splitlines()[2:] for p in PATH.findall(row.split("|")[2])]
    assert len(now) >= 10 and [p for p in now if not os.path.exists(os.path.join(ROOT, p))] == []


SECTION = re.compile(r'docs/(benchmarks|history|tasks|guide|tensor_api)\.md(?:, | \()"([^"]+)"')


def titles(page: str) -> set[str]:
    """A page's headings and the bold titles that open its paragraphs, whitespace folded."""
    text = read(f"docs/{page}.md")
    found = [line.lstrip("#").strip() for line in text.splitlines() if line.startswith("#")]
    found += re.findall(r"^\*\*([^*]+)\*\*", text, re.M)
    return {" ".join(t.split()) for t in found}


def test_every_section_a_page_or_the_code_cites_by_name_is_on_that_page():
    """``docs/benchmarks.md, "Overlapped update"`` and the like, in the docs and in comments: the named heading (or
    bold title) is on the named page, so a section moved to the log cannot leave its citations behind."""
    files = PAGES + ["docs/benchmarks.md", "docs/history.md"]
    for top in ("warpgym", "agents", "kernels", "benchmarks", "scripts"):
        for folder, _, names in os.walk(os.path.join(ROOT, top)):
            files += [os.path.relpath(os.path.join(folder, n), ROOT) for n in names if n.endswith(".py")]
    cache, stale = {}, []
    for file in files:
        for page, title in SECTION.findall(read(file)):
            title = " ".join(title.split())
            have = cache.setdefault(page, titles(page))
            if not any(h.startswith(title) or title.startswith(h) for h in have):
                stale.append(f"{file}: docs/{page}.md, \"{title}\"")
    assert not stale, stale


def test_the_rough_native_replay_table_is_the_committed_evaluations():
    """docs/tasks.md's native-MuJoCo table of the rough Go1: each kind's tracking error xy, native / warpgym, at levels
    2 and 5, as `warpgym eval --level L --json` wrote them; the overall ratios it states too."""
    import json

    with open(os.path.join(ROOT, "docs", "tasks.md")) as f:
        page = f.read()
    for level in (2, 5):
        with open(os.path.join(ROOT, "docs", "bench", "legged", f"native_Go1VelocityRough-v0_level{level}.json")) as f:
            got = json.load(f)
        assert got["level"] == level
        native, ours = got["native"]["errors_by_kind"], got["warpgym"]["errors_by_kind"]
        for kind in native:
            assert f"{native[kind][0]:.3f} / {ours[kind][0]:.3f}" in page, (level, kind)
        assert f"{got['error_xy_ratio']:.2f}x (level\n{level})" in page or f"{got['error_xy_ratio']:.2f}x (level {level})" in page
