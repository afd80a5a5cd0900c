"""What the benchmarks time training against, one table for all of them, and what a run reached.

warpgym's robots: the training episodes' mean forward speed [m/s]: the first is "walking" (docs/benchmarks.md's
time-to-walk figures, the fidelity and learner tables, the RLlib comparison), the second a trained gait (the
envs-per-GPU and overlap runs). Gymnasium's suite: the published return each task is held to (``REFERENCE``:
Tianshou's MuJoCo benchmark for SAC, SLM-Lab's where Tianshou has none), with its source and the task version
it was made on.
"""

TARGETS = {"Ant": (3.0, 8.0), "Humanoid": (2.0, 6.0)}
WALKING = {task: speeds[0] for task, speeds in TARGETS.items()}

REFERENCE = {"Ant-v5": 5850.2, "HalfCheetah-v5": 12138.8, "Hopper-v5": 3542.2, "Walker2d-v5": 5007.0,
             "Swimmer-v5": 44.4, "Humanoid-v5": 5488.5, "Reacher-v5": -2.6, "InvertedPendulum-v5": 1000.0,
             "InvertedDoublePendulum-v5": 9359.5, "Pusher-v5": -42.6, "HumanoidStandup-v5": 138222.0}
REFERENCE_SOURCE = {task: "Tianshou SAC" for task in REFERENCE} | {"Pusher-v5": "SLM-Lab SAC",
                                                                  "HumanoidStandup-v5": "SLM-Lab SAC"}
# the task versions the figures were made on (v5's Pusher and HumanoidStandup: SLM-Lab's)
REFERENCE_VERSION = {task: "v3" for task in REFERENCE} | {"Reacher-v5": "v2", "InvertedPendulum-v5": "v2",
                                                         "InvertedDoublePendulum-v5": "v2", "Pusher-v5": "v5",
                                                         "HumanoidStandup-v5": "v5"}


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
