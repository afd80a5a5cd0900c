"""The docs' generated tables (benchmarks/doc_tables.py): every block on its page is its report of the committed
JSON, word for word, and a block edited by hand or a report that changed is caught."""

import os

import pytest

from benchmarks import doc_tables

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


@pytest.mark.parametrize("name", sorted(doc_tables.BLOCKS))
def test_each_block_on_its_page_is_what_its_report_prints(name):
    page = doc_tables.BLOCKS[name][0]
    blocks = doc_tables.blocks_on(page)
    assert name in blocks, f"{page} has no block {name!r}"
    assert blocks[name] == doc_tables.generate(name)


def test_no_page_holds_a_block_the_registry_does_not_know():
    names = set()
    for page in ("README.md", *(os.path.join("docs", p) for p in os.listdir(os.path.join(ROOT, "docs")) if p.endswith(".md"))):
        names |= set(doc_tables.blocks_on(page))
    assert names == set(doc_tables.BLOCKS)


def test_a_hand_edited_row_and_a_missing_block_are_reported(tmp_path, monkeypatch):
    """A copy of the pages with one figure changed and one block's markers gone: --check names both."""
    (tmp_path / "docs").mkdir()
    os.symlink(os.path.join(ROOT, "docs", "bench"), tmp_path / "docs" / "bench")
    with open(os.path.join(ROOT, "README.md")) as f:
        readme = f.read()
    with open(os.path.join(ROOT, "docs", "benchmarks.md")) as f:
        bench = f.read()
    assert "| Ant-v5 | **8015** (7848 to 8181)" in readme
    (tmp_path / "README.md").write_text(readme.replace("| Ant-v5 | **8015** (7848 to 8181)", "| Ant-v5 | **8115** (7848 to 8181)"))
    (tmp_path / "docs" / "benchmarks.md").write_text(bench.replace("<!-- table: suite-speed -->", ""))
    for page in ("history.md", "tasks.md"):  # the log holds the blocks of tables moved there; tasks.md its terms'
        with open(os.path.join(ROOT, "docs", page)) as f:
            (tmp_path / "docs" / page).write_text(f.read())
    monkeypatch.setattr(doc_tables, "ROOT", str(tmp_path))
    problems = doc_tables.check()
    assert any("'readme-learning' differs" in p and "+| Ant-v5 | **8015**" in p for p in problems)
    assert any("no block 'suite-speed'" in p for p in problems)
    assert len(problems) == 2
    doc_tables.write()
    assert "| Ant-v5 | **8015** (7848 to 8181)" in (tmp_path / "README.md").read_text()


def test_the_readme_speed_tables_widths_are_the_envs(ant_env, humanoid_env):
    """benchmarks/speed/readme_speed.py writes each task's observation and action widths by hand: they are the envs'."""
    from benchmarks.speed.readme_speed import ROWS
    from warpgym.envs import make_vec_env
    from warpgym.envs.legged import LeggedVecEnv

    built = {"warpgym/Ant-v0": ant_env, "warpgym/Humanoid-v0": humanoid_env}
    for name, widths, (kind, what, _) in ROWS:
        if name not in built:
            built[name] = (LeggedVecEnv(what, num_envs=1, device="cpu") if kind == "legged"
                           else make_vec_env(what, num_envs=1, device="cpu"))
        env = built[name]
        obs, actions = env.single_observation_space.shape[0], env.single_action_space.shape[0]
        critic = getattr(env, "num_critic_obs", 0)
        assert widths == (f"{obs} (critic {critic}) / {actions}" if critic else f"{obs} / {actions}"), name
