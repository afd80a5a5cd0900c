"""How a data-parallel run divides its work among G processes (one per GPU): ``Config.multi_gpu``.

Every mode trains one policy, its gradients averaged over the processes at each mini-batch step
(agents.distributed); they differ in what grows with G:

``split``       strong scaling: ``num_envs`` and the mini-batch (``minibatch_size``) are the run's totals, each
                process steps num_envs / G envs and holds minibatch_size / G samples of every mini-batch. An
                iteration is the one-GPU algorithm step for step (the same samples, mini-batches and
                optimiser steps), on envs that step faster because each GPU holds fewer: more iterations
                per second, the same learning per iteration.
``split-horizon`` strong scaling in time: each process steps num_envs envs for horizon_len / G steps, and a
                mini-batch is minibatch_size samples across the processes, as under ``split``. An iteration is the
                one-GPU run's batch (as many samples, mini-batches and optimiser steps) from G times the envs over
                a G times shorter horizon. Each GPU steps as many envs as one GPU alone, for 1/G of the steps, so
                the rollout takes about 1/G of the time whatever a step costs; ``split``'s fewer envs per GPU gain
                only where a step's time grows with its envs, which MuJoCo Warp's does not at a few thousand
                worlds (bound by its launches). What changes is the horizon: GAE bootstraps from the value
                G times as often.
``grow-batch``  weak scaling, the mini-batch grows: each process steps num_envs envs and mini-batches of
                minibatch_size, so an optimiser step averages G times the samples of a one-GPU step; an
                iteration takes about as long as on one GPU.
``grow-steps``  weak scaling, the mini-batch stays: each process steps num_envs envs, a mini-batch stays
                minibatch_size samples across all processes, so an iteration makes G times the optimiser
                steps (Beukman et al., 2026, keep the inner loop fixed as the envs grow).
``grow-kl``     grow-steps with the KL target (``Config.desired_kl``) G times as wide. The learning-rate rule
                holds each mini-batch's policy within about desired_kl of the policy that drew the rollout, so
                under grow-steps G times the steps on G times the samples still move the policy one KL target
                per iteration and learn per iteration what one GPU learns (the Humanoid on 2 GPUs: as many
                iterations to 6 m/s, at a lower learning rate). Widened with the data, the iteration moves as
                far as its samples support.

``grow-kl`` is the default (DEFAULT) and the preset of warpgym's Ant and Humanoid: on 2 GPUs it brought the
Humanoid to 6 m/s in at most 0.53x of one GPU's learning time, where grow-steps took 1.08x and split 1.50x; the same
wider target on one GPU was no sooner. On 4 H200s it took the Ant to 9.5 m/s in 0.30x and the Humanoid to 6 m/s in
0.33x. Gymnasium's tasks preset ``split-horizon`` (warpgym.tasks.presets): there an iteration under grow-kl learnt only
1.1-2.1x what one GPU's did, while split-horizon's 4 H200s took Ant-v5 to 5850 in 0.26x and Humanoid-v5 to 10000 in
under 0.45x. docs/benchmarks.md, "Several GPUs: time to target", has what each mode gave on each task.
With one process every mode is the same run.
"""

from __future__ import annotations

MODES = ("split", "split-horizon", "grow-batch", "grow-steps", "grow-kl")
DEFAULT = "grow-kl"


def check_mode(mode: str) -> str:
    if mode not in MODES:
        raise ValueError(f"multi_gpu={mode!r}: choose one of {', '.join(MODES)} (agents/data_parallel.py)")
    return mode


def envs_per_process(mode: str, num_envs: int, processes: int) -> int:
    """The envs one process steps when the run asks for ``num_envs`` (the total under ``split``)."""
    check_mode(mode)
    if mode != "split" or processes == 1:
        return num_envs
    if num_envs % processes:
        raise ValueError(f"num_envs={num_envs} does not split over {processes} processes (multi_gpu='split': "
                         f"num_envs is the run's total): pick a multiple of {processes}, e.g. "
                         f"{max(processes, num_envs // processes * processes)}")
    return num_envs // processes


def horizon_per_process(mode: str, horizon_len: int, processes: int) -> int:
    """The steps one process collects per iteration when the run asks for ``horizon_len`` (the total under
    ``split-horizon``)."""
    check_mode(mode)
    if mode != "split-horizon" or processes == 1:
        return horizon_len
    if horizon_len % processes:
        multiple = max(processes, horizon_len // processes * processes)
        raise ValueError(f"horizon_len={horizon_len} does not split over {processes} processes (multi_gpu="
                         f"'split-horizon': horizon_len is the run's total): pick a multiple of {processes}, e.g. "
                         f"horizon_len={multiple}")
    return horizon_len // processes


def kl_target(mode: str, desired_kl: float, processes: int) -> float:
    """The KL target the learning-rate rule steers each mini-batch to among ``processes``; 0 (the rule off) stays 0."""
    check_mode(mode)
    return desired_kl * processes if mode == "grow-kl" else desired_kl


def minibatches(mode: str, local_envs: int, horizon_len: int, minibatch_size: int, processes: int = 1) -> int:
    """Mini-batch steps per pass over a rollout, the same on every process; raises where the samples do not
    divide. ``local_envs`` is this process's envs and ``horizon_len`` the run's (``horizon_per_process``);
    ``minibatch_size`` is a mini-batch's samples across all processes, except under ``grow-batch``, where it is
    each process's."""
    check_mode(mode)
    shared = mode != "grow-batch" and processes > 1
    if shared and minibatch_size % processes:
        raise ValueError(f"minibatch_size={minibatch_size} does not split over {processes} processes "
                         f"(multi_gpu={mode!r}: a mini-batch is {minibatch_size} samples across them): "
                         f"pick a multiple of {processes}")
    steps = horizon_per_process(mode, horizon_len, processes)
    samples = local_envs * steps * (processes if shared else 1)  # the rollout a mini-batch is drawn from
    rollout = (f"{processes} processes x " if shared else "") + f"{local_envs} envs x {steps} steps"
    if minibatch_size > samples:
        raise ValueError(f"minibatch_size={minibatch_size} exceeds the {samples} samples of one rollout ({rollout}): "
                         "lower minibatch_size or raise num_envs")
    if samples % minibatch_size:
        raise ValueError(f"minibatch_size={minibatch_size} does not divide the {samples} samples of one rollout "
                         f"({rollout}): pick a divisor, e.g. {samples // 4}")
    return samples // minibatch_size
