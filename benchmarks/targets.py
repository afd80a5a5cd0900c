"""The speeds the benchmarks time training against, one table for all of them, and what a run reached.

The training episodes' mean forward speed [m/s]: the first is "walking" (docs/benchmarks.md's
time-to-walk figures, the fidelity and learner tables, the RLlib comparison), the second a trained
gait (issue 31's envs-per-GPU and overlap runs).
"""

TARGETS = {"Ant": (3.0, 8.0), "Humanoid": (2.0, 6.0)}
WALKING = {task: speeds[0] for task, speeds in TARGETS.items()}


def walking_row(run_dir: str, task: str) -> dict:
    """A run's samples/s (the median past the first fifth), first row, when its training episodes first
    reached the task's walking speed, and its last return and speed, from its metrics.jsonl ({"error": ...}
    without one)."""
    from agents.logger import first_reaching, read_metrics, steady_median

    try:
        rows = read_metrics(run_dir)
    except FileNotFoundError:
        return {"error": "no metrics"}
    done = [r for r in rows if r.get("speed") is not None]
    hit = first_reaching(rows, "speed", WALKING[task]) or {}
    return {"iterations": len(rows), "samples": rows[-1]["samples"] if rows else 0,
            "samples_per_s": steady_median(rows), "first_row_s": rows[0]["time_s"] if rows else None,
            "target_speed": WALKING[task], "time_to_target_s": hit.get("time_s"),
            "samples_to_target": hit.get("samples"), "final_return": done[-1]["return"] if done else None,
            "final_speed": done[-1]["speed"] if done else None}
