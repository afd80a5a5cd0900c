"""Episodic reward against wall-clock time and against samples: the two views of a run ElegantRL's Isaac Gym
tutorial draws; under them, where a run logs a curriculum (``curriculum/<name>``: the rough tasks' mean terrain
level), its state on the same axis."""

from __future__ import annotations

import os

from agents.logger import read_metrics

AXES = {"time": ("time_s", "wall-clock time since process start [s]"), "samples": ("samples", "samples (env steps)")}


def _series(rows: list[dict], x_key: str, y_key: str):
    pts = [(r[x_key], r[y_key]) for r in rows if r.get(y_key) is not None and r.get(x_key) is not None]
    return [p[0] for p in pts], [p[1] for p in pts]


def curriculum_keys(runs: list[list[dict]]) -> list[str]:
    """The ``curriculum/<name>`` keys any of the runs' rows logged, sorted."""
    return sorted({k for rows in runs for r in rows for k in r if k.startswith("curriculum/")})


def plot_runs(run_dirs: list[str], out_dir: str, labels: list[str] | None = None, title: str = "") -> list[str]:
    """Write reward_vs_time.png and reward_vs_samples.png into ``out_dir`` (with a panel per curriculum key under
    the return, where the runs log one); return their paths."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    labels = labels or [os.path.basename(os.path.normpath(d)) for d in run_dirs]
    runs = [read_metrics(d) for d in run_dirs]
    os.makedirs(out_dir, exist_ok=True)
    paths = []
    extra = curriculum_keys(runs)
    for name, (x_key, x_label) in AXES.items():
        fig, axes = plt.subplots(1 + len(extra), 1, figsize=(7, 4.5 + 2.2 * len(extra)), sharex=True, squeeze=False,
                                 gridspec_kw={"height_ratios": [2] + [1] * len(extra)})
        ax = axes[0][0]
        for (panel,), key in zip(axes[1:], extra):
            for rows, label in zip(runs, labels):
                panel.plot(*_series(rows, x_key, key), label=label)
            panel.set_ylabel(key.split("/", 1)[1].replace("_", " "))
            panel.grid(alpha=0.3)
        for rows, label in zip(runs, labels):
            x, y = _series(rows, x_key, "return")
            line = ax.plot(x, y, label=f"{label}: training episodes (stochastic)")[0]
            ex, ey = _series(rows, x_key, "eval/return")
            if ex:
                ax.plot(ex, ey, "o--", color=line.get_color(), label=f"{label}: deterministic policy")
        axes[-1][0].set_xlabel(x_label)
        ax.set_ylabel("mean episodic return")
        ax.set_title(title or "episodic return")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = os.path.join(out_dir, f"reward_vs_{name}.png")
        fig.savefig(path + ".tmp.png", dpi=110)
        os.replace(path + ".tmp.png", path)
        plt.close(fig)
        paths.append(path)
    return paths
