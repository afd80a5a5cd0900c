"""``warpgym eval`` of Gymnasium's suite: the policy in ``gymnasium.make``'s env (v5, and v4 on demand) and, from
the same starts, in warpgym's."""

from __future__ import annotations

from warpgym.cli.eval import holds, mean_terms, parser, terms_line


def gymnasium_side(task, act, episodes: int, seeds: list[int], unit: bool, version: int = 5,
                   starts: list | None = None, nudge: float = 0.0) -> dict:
    """The policy's episodes in ``gymnasium.make`` of the task (v5, or v4): ``episodes`` from reset seed
    1000 s on, for each s of ``seeds`` (``gymnasium_policy_episodes``' starts, nudge and version)."""
    import numpy as np  # noqa: PLC0415

    from warpgym.native.suite import gymnasium_policy_episodes  # noqa: PLC0415

    per_seed, returns, lengths, terms = [], [], [], {}
    for seed in seeds:
        r, n = gymnasium_policy_episodes(task, act, episodes, seed=1000 * seed, unit_actions=unit, starts=starts,
                                         nudge=nudge, terms=terms, version=version)
        per_seed.append({"seed": seed, "return": float(r.mean()), "length": float(n.mean())})
        returns += r.tolist()
        lengths += n.tolist()
    return {"return": float(np.mean(returns)), "std": float(np.std(returns)), "length": float(np.mean(lengths)),
            "per_seed": per_seed, "terms": mean_terms(terms), "returns": returns, "lengths": lengths}


def evaluate(args, ckpt: dict, name: str, device: str, env_args: dict, entry) -> int:
    """A policy of Gymnasium's suite in ``gymnasium.make``'s env (and, from the same starts, in warpgym's)."""
    import numpy as np  # noqa: PLC0415
    import torch  # noqa: PLC0415

    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.cli import write_json  # noqa: PLC0415
    from warpgym.envs import make_vec_env  # noqa: PLC0415
    from warpgym.native.suite import v4_tasks, warpgym_policy_episodes  # noqa: PLC0415
    from warpgym.tasks.suite import get_suite_task  # noqa: PLC0415

    path = args.checkpoint_path
    trained = get_suite_task(name)
    if args.env_version == 4 and trained.v4_observation is None:
        parser().error(f"--env-version 4: {name}'s v4 observation is not v5's plus entries after it (or v4 needs "
                       f"MuJoCo < 3), so a v5 policy cannot play it; v4 is scored for {v4_tasks()}")
    unit = bool(env_args.get("unit_actions", False))
    # Gymnasium's env knows Gymnasium's terms only: a task's own rewards and terminations shaped its training, and
    # both envs score it without them
    task = trained.gymnasiums_terms_only()
    if env_args.get("max_episode_steps"):
        task = task.replace(episode_length=int(env_args["max_episode_steps"]))
    episodes = args.episodes * len(args.seeds)
    env = make_vec_env(task, num_envs=episodes, device=device, seed=args.seeds[0], unit_actions=unit,
                       max_episode_steps=task.episode_length)
    policy, normalize = policy_from_checkpoint(ckpt, env.num_obs, env.num_actions, torch.device(device))

    def act(obs):
        return policy.act_deterministic(normalize(obs.to(device))).cpu()

    starts = []
    gym = gymnasium_side(task, act, args.episodes, args.seeds, unit, starts=starts)
    # the same episodes in warpgym: each world starts where one of Gymnasium's episodes started
    ours_terms = {}
    ours_r, ours_n = warpgym_policy_episodes(env, lambda obs: policy.act_deterministic(normalize(obs)), starts,
                                             terms=ours_terms)
    env.close()
    ours = {"eval/return": float(ours_r.mean()), "eval/length": float(ours_n.mean())}
    gym_return = gym["return"]
    ratio = holds(gym_return, ours["eval/return"])
    extra = {}
    if args.nudge:
        moved = gymnasium_side(task, act, args.episodes, args.seeds, unit, nudge=args.nudge)["return"]
        extra = {"nudge": args.nudge, "gymnasium_nudged_return": moved,
                 "gymnasium_over_gymnasium_nudged": holds(gym_return, moved)}
    if args.env_version == 4:
        old = gymnasium_side(task, act, args.episodes, args.seeds, unit, version=4)
        extra = {"v4_return": old["return"], "v4_return_std": old["std"], "v4_length": old["length"],
                 "v4_per_seed": old["per_seed"], "v4_terms": old["terms"],
                 "v4_over_v5": holds(old["return"], gym_return)}
    result = {"task": name, "checkpoint": path, "iteration": ckpt["iteration"], "samples": ckpt["samples"],
              "episodes": episodes, "gymnasium_return": gym_return, "gymnasium_return_std": gym["std"],
              "gymnasium_length": gym["length"], "per_seed": gym["per_seed"], "gymnasium_terms": gym["terms"],
              "warpgym_return": ours["eval/return"], "warpgym_length": ours["eval/length"],
              "warpgym_return_std": float(np.std(ours_r)), "warpgym_terms": mean_terms(ours_terms),
              "same_starts": True, "gymnasium_over_warpgym": ratio,
              # episode by episode, paired (the same start in both envs): a mean hides a knife edge, a robot that
              # falls or flips in a few episodes
              "gymnasium_returns": gym["returns"], "gymnasium_lengths": gym["lengths"],
              "warpgym_returns": ours_r.tolist(), "warpgym_lengths": ours_n.tolist(), **extra}
    if args.normalizer_from:
        result.update(normalizer_from=args.normalizer_path, normalizer_iteration=args.normalizer_iteration)
    if ckpt["config"].get("normalize_obs"):  # the statistics the policy was played with: where do they drift?
        stats = ckpt["normalizer"]
        result.update(normalizer_mean=stats["mean"].tolist(), normalizer_std=stats["var"].sqrt().tolist())
    print(f"{name}, policy of iteration {ckpt['iteration']} ({ckpt['samples'] / 1e6:.2f} M samples), deterministic, "
          f"{episodes} episodes each:")
    print(f"  Gymnasium's env (gymnasium.make, float64): return {gym_return:.1f} ± {gym['std']:.1f}, "
          f"length {gym['length']:.0f}   per seed: "
          + ", ".join(f"{s['seed']}: {s['return']:.1f}" for s in gym["per_seed"]))
    own = [*trained.rewards, *trained.terminations]
    if own:
        print(f"  both envs score Gymnasium's reward and terminations alone: the task's own terms {own} shaped "
              "its training only")
    print(f"  warpgym's env (float32, {device}), the same starts: return {ours['eval/return']:.1f} "
          f"± {np.std(ours_r):.1f}, length {ours['eval/length']:.0f}")
    print("  reward terms, mean per episode (Gymnasium | warpgym): " + terms_line(
        {"gymnasium": gym["terms"], "warpgym": result["warpgym_terms"]},
        {"gymnasium": gym_return, "warpgym": ours["eval/return"]},
        {"gymnasium": gym["length"], "warpgym": ours["eval/length"]}))
    print(f"  held in Gymnasium's env (Gymnasium / warpgym; for costs warpgym / Gymnasium): {ratio:.3f}")
    if args.nudge:
        print(f"  Gymnasium's env, every start moved by {args.nudge:g}: "
              f"return {extra['gymnasium_nudged_return']:.1f}; "
              f"Gymnasium / itself so moved: {extra['gymnasium_over_gymnasium_nudged']:.3f}")
    if args.env_version == 4:
        print(f"  Gymnasium's v4 ({task.version_name(4)}), the same reset seeds: return {old['return']:.1f} "
              f"± {old['std']:.1f}, length {old['length']:.0f}; v4 / v5 (for costs v5 / v4): {extra['v4_over_v5']:.3f}")
        print("  reward terms, mean per episode (v5 | v4): " + terms_line(
            {"v5": gym["terms"], "v4": old["terms"]}, {"v5": gym_return, "v4": old["return"]},
            {"v5": gym["length"], "v4": old["length"]}))
    if args.json:
        write_json(args.json, result)
    print(f"Next: warpgym play {args.checkpoint} --gif {name.lower()}.gif draws it"
          + (f" (the numbers: {args.json})." if args.json else " (--json OUT writes the numbers)."))
    return 0
