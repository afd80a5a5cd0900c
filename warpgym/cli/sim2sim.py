"""Sim-to-sim check of a trained policy: does its gait survive a finer physics step and a second simulator?

    warpgym sim2sim runs/Ant-20261122-120000            # its checkpoint.pt
    warpgym sim2sim runs/Ant-.../checkpoint-500.pt --envs 256 --native-copies 16 --out s2s.json

Plays the deterministic policy for one episode (--steps control steps) in four settings:
    warpgym        at the training step (the checkpoint's substeps) and at --finer times as many substeps
    native MuJoCo  the same MJCF in the ``mujoco`` package (C, CPU, float64), at the training step and
                   --finer times finer, with the observation and action mapping computed from MuJoCo's
                   own data (warpgym/native/robots.py)
and prints for each: forward speed (each robot's first episode: the distance it travelled towards the
target over the time until it fell or the replay ended, warpgym's one definition; the mean over
robots), torso height while up, falls, the largest joint speed, and the share of steps with no foot on
the ground and the longest such stretch; the ratio columns divide by warpgym's training-step speed. A
gait that only works at the training step exploits the integrator, not the robot.
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np

from warpgym.cli import write_json
from warpgym.cli.flags import CommandParser, check_checkpoint, check_device, non_negative_int, positive_int


class GaitMeter:
    """Per-episode gait statistics from per-step arrays of K robots; a robot counts until it first ends."""

    def __init__(self, k: int, contact_measure: str):
        self.k, self.steps, self.contact_measure = k, 0, contact_measure
        self.up = np.ones(k, bool)
        self.speed, self.z, self.up_steps, self.airborne = np.zeros(k), np.zeros(k), np.zeros(k), np.zeros(k)
        self.stretch, self.longest_stretch = np.zeros(k), np.zeros(k)
        self.peak_joint_speed = 0.0

    def add(self, speed, z, dof_vel, touching, ended) -> None:
        """speed (K,): the forward speed of each robot's episode so far (LocomotionTask.forward_speed),
        kept from the step it ended; z (K,); dof_vel (K, A); touching (K,) bool: a foot was on the
        ground in this step; ended (K,) bool: fell or timed out at this step."""
        up = self.up
        self.steps += 1
        self.speed = np.where(up, speed, self.speed)
        self.z += z * up
        self.up_steps += up
        flying = ~touching & up
        self.airborne += flying
        self.stretch = np.where(flying, self.stretch + 1, 0)
        self.longest_stretch = np.maximum(self.longest_stretch, self.stretch)
        if up.any():
            self.peak_joint_speed = max(self.peak_joint_speed, float(np.abs(dof_vel[up]).max()))
        self.up = up & ~ended

    def result(self, fell: np.ndarray) -> dict:
        alive_steps = max(self.up_steps.sum(), 1.0)
        return {"forward_speed": float(self.speed.mean()),
                "torso_height": float(self.z.sum() / alive_steps),
                "falls": int(fell.sum()), "robots": self.k,
                "peak_joint_speed": self.peak_joint_speed,
                "no_foot_contact_share": float(self.airborne.sum() / alive_steps),
                "longest_airborne_steps": float(np.median(self.longest_stretch)),
                "contact_measure": self.contact_measure}


def feet_pressed(feet_obs: np.ndarray, k: int) -> np.ndarray:
    """(K,) bool from the observation's foot columns: some foot felt a contact force."""
    return (np.abs(feet_obs.reshape(k, -1, 6)[..., :3]) > 0).any(axis=(1, 2))


def feet_columns(task, num_actions: int, num_feet: int) -> slice:
    from warpgym.native.robots import observation_slices  # noqa: PLC0415

    return observation_slices(task, num_actions, num_feet)["feet"]


def replay_warpgym(ckpt, env_args: dict, substeps: int, envs: int, steps: int, device: str, seed: int) -> dict:
    import torch  # noqa: PLC0415

    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.envs import LocomotionVecEnv  # noqa: PLC0415
    from warpgym.sim.physics import recorded  # noqa: PLC0415

    env = LocomotionVecEnv(env_args["task"], num_envs=envs, device=device, seed=seed, substeps=substeps,
                           physics=recorded(env_args.get("physics")), max_episode_steps=steps)
    policy, normalize = policy_from_checkpoint(ckpt, env.num_obs, env.num_actions, torch.device(device))
    result = play_warpgym(env, lambda obs: policy.act_deterministic(normalize(obs)), steps, seed)
    env.close()
    return result


def play_warpgym(env, act, steps: int, seed: int) -> dict:
    """``steps`` control steps of ``act`` (observations -> actions, torch) in a ``LocomotionVecEnv``."""
    import torch  # noqa: PLC0415

    envs = env.num_envs
    feet = feet_columns(env.task, env.num_actions, env.sim.foot_bodies.shape[0])
    meter = GaitMeter(envs, "foot contact force in the last substep of a step")
    fell = np.zeros(envs, bool)
    obs, _ = env.reset(seed=seed)
    with torch.no_grad():
        for _ in range(steps):
            obs, _, terminated, truncated, info = env.step(act(obs))
            done = terminated | truncated
            ended = done.cpu().numpy()
            fell |= terminated.cpu().numpy() & meter.up
            # a robot that ended was reset inside the step: its pose is the new episode's, its
            # observation row the new episode's first; its speed is the env's record of the one that ended
            speed = torch.where(done, info["episode"]["s"], info["episode_so_far"]["s"])
            meter.add(speed.cpu().numpy(), env.sim.root_pose[:, 2].cpu().numpy(),
                      env.sim.dof_vel.cpu().numpy(), feet_pressed(obs[:, feet].cpu().numpy(), envs), ended)
    return meter.result(fell)


def replay_native(ckpt, env_args: dict, substeps: int, copies: int, steps: int, seed: int, account=None) -> dict:
    """``play_native`` of a checkpoint's policy; ``account`` (made from the MjModel: a ``NativeRobot.on_substep``
    with a ``watts()``, as benchmarks/physics/energy.py's ``PowerMeter``) adds ``power_w``, its mean watts per robot
    until the robot's fall."""
    import torch  # noqa: PLC0415

    from agents.checkpoint import policy_from_checkpoint  # noqa: PLC0415
    from warpgym.native.robots import NativeRobot  # noqa: PLC0415
    from warpgym.tasks.robots import trained_task  # noqa: PLC0415

    task = trained_task(env_args)
    robot = NativeRobot(task, substeps=substeps, copies=copies)
    num_obs = task.observation_size(len(robot.dof_names), len(robot.feet))
    policy, normalize = policy_from_checkpoint(ckpt, num_obs, len(robot.dof_names), torch.device("cpu"))
    meter = robot.on_substep = account(robot.model) if account else None
    row = play_native(robot, lambda obs: policy.act_deterministic(normalize(obs)), steps, seed)
    return {**row, "power_w": meter.watts()} if meter else row


def play_native(robot, act, steps: int, seed: int) -> dict:
    """``steps`` control steps of ``act`` (observations -> actions, torch) on a ``NativeRobot``; each
    robot stops at its first fall."""
    import torch  # noqa: PLC0415

    task, copies = robot.task, robot.copies
    meter = GaitMeter(copies, "a foot within the contact margin of the ground in any substep of a step")
    fell = np.zeros(copies, bool)
    robot.reset(np.random.default_rng(seed))
    start = robot.state()["root_pose"][:, :3]
    actions = np.zeros((copies, len(robot.dof_names)))
    obs = robot.observation(actions, fresh=True)
    with torch.no_grad():
        for step in range(1, steps + 1):
            actions = robot.step(act(torch.as_tensor(obs, dtype=torch.float32)).numpy(), active=meter.up)
            obs = robot.observation(actions)
            s = robot.state()
            down = s["root_pose"][:, 2] < task.termination_height
            fell |= down & meter.up
            speed = task.forward_speed(s["root_pose"][:, :3] - start, step)
            meter.add(speed, s["root_pose"][:, 2], s["dof_vel"], robot.feet_touched, down)
    return meter.result(fell)


def parser() -> CommandParser:
    ap = CommandParser(prog="warpgym sim2sim", description=__doc__)
    ap.add_argument("checkpoint", help="a checkpoint file, or a run directory holding checkpoint.pt")
    ap.add_argument("--envs", type=positive_int(256), default=None,
                    help="warpgym robots per setting (default 256 GPU, 8 CPU)")
    ap.add_argument("--native-copies", type=positive_int(16), default=16, help="native MuJoCo robots per setting")
    ap.add_argument("--steps", type=positive_int(1000), default=1000, help="control steps (one episode at most)")
    ap.add_argument("--finer", type=positive_int(4), default=4, help="how many times finer the second physics step is")
    ap.add_argument("--no-native", action="store_true", help="warpgym settings only")
    ap.add_argument("--device", default=None)
    ap.add_argument("--seed", type=non_negative_int(7), default=7)
    ap.add_argument("--out", default=None, help="also write the rows to this JSON file")
    return ap


def main(argv=None) -> int:
    ap = parser()
    args = ap.parse_args(argv)
    check_checkpoint(ap, args.checkpoint)
    check_device(ap, args.device)

    import torch  # noqa: PLC0415

    from agents.checkpoint import load, load_for_command  # noqa: PLC0415
    from warpgym.sim.device import resolve_device  # noqa: PLC0415
    from warpgym.tasks.robots import get_task  # noqa: PLC0415

    device = resolve_device(args.device)
    envs = args.envs or (256 if device.startswith("cuda") else 8)
    path, ckpt = load_for_command(args.checkpoint, torch.device(device))
    env_args = ckpt["config"]["env_args"]
    task = get_task(env_args["task"])
    trained = int(env_args.get("substeps") or task.substeps)
    finer = trained * args.finer

    rows = []

    def record(sim: str, substeps: int, result: dict, seconds: float) -> None:
        row = {"simulator": sim, "substeps": substeps, "physics_dt": task.dt / substeps, **result,
               "wall_s": round(seconds, 2)}
        rows.append(row)
        print(json.dumps(row), flush=True)

    for substeps in (trained, finer):
        t0 = time.perf_counter()
        record("warpgym", substeps, replay_warpgym(ckpt, env_args, substeps, envs, args.steps, device, args.seed),
               time.perf_counter() - t0)
    if not args.no_native:
        ckpt_cpu = load(path, torch.device("cpu"))
        for substeps in (trained, finer):
            t0 = time.perf_counter()
            record("native MuJoCo", substeps,
                   replay_native(ckpt_cpu, env_args, substeps, args.native_copies, args.steps, args.seed),
                   time.perf_counter() - t0)
    base = rows[0]["forward_speed"]
    for row in rows:
        row["speed_ratio"] = row["forward_speed"] / base if base else float("nan")

    print(f"\n{env_args['task']} policy from iteration {ckpt['iteration']} ({ckpt['samples'] / 1e6:.1f} M samples), "
          f"trained with {trained} substeps, physics {env_args.get('physics') or 'default'}")
    print("| simulator | physics step | forward speed | ratio | torso height | falls | peak joint speed | "
          "no foot on ground | longest flight |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['simulator']} | 1/{round(1 / r['physics_dt'])} s | {r['forward_speed']:.2f} m/s | "
              f"{r['speed_ratio']:.2f} | {r['torso_height']:.2f} m | {r['falls']}/{r['robots']} | "
              f"{r['peak_joint_speed']:.0f} rad/s | {100 * r['no_foot_contact_share']:.0f} % | "
              f"{r['longest_airborne_steps']:.0f} steps |")
    print("no foot on ground: warpgym counts a step when no foot felt a force in its last substep; native "
          "MuJoCo when no foot came within the contact margin in any substep. Longest flight: the median "
          "robot's longest run of such steps.")
    if args.out:
        out = {"checkpoint": path, "iteration": ckpt["iteration"], "samples": ckpt["samples"],
               "task": env_args["task"], "trained_substeps": trained, "physics": env_args.get("physics") or {},
               "device": device, "rows": rows}
        write_json(args.out, out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
