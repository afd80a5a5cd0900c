"""An independent torch implementation of the locomotion observation and reward, written from
shared/specs/tasks.md and fed only by the Tensor API, to check the Warp kernels against."""

from __future__ import annotations

import math

import torch


def quat_rotate_inverse(q: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    """Rotate v by the inverse of xyzw quaternion q."""
    xyz, w = q[:, :3], q[:, 3:4]
    t = 2.0 * torch.cross(xyz, v, dim=1)
    return v - w * t + torch.cross(xyz, t, dim=1)


def quat_rotate(q: torch.Tensor, v: torch.Tensor) -> torch.Tensor:
    xyz, w = q[:, :3], q[:, 3:4]
    t = 2.0 * torch.cross(xyz, v, dim=1)
    return v + w * t + torch.cross(xyz, t, dim=1)


def wrap(a: torch.Tensor) -> torch.Tensor:
    return torch.remainder(a + math.pi, 2 * math.pi) - math.pi


def potentials(root_state: torch.Tensor, task) -> torch.Tensor:
    d = torch.tensor(task.target, dtype=torch.float32) - root_state[:, :3]
    return -torch.linalg.norm(d[:, :2], dim=1) / task.dt


def observation(sim, task, actions: torch.Tensor) -> torch.Tensor:
    """The observation after a step, from refreshed Tensor API buffers."""
    n, a = sim.num_envs, sim.num_dofs
    root = sim.acquire_actor_root_state_tensor()
    dof = sim.acquire_dof_state_tensor().view(n, a, 2)
    pos, q, lin, ang = root[:, :3], root[:, 3:7], root[:, 7:10], root[:, 10:13]
    to_target = torch.tensor(task.target, dtype=torch.float32) - pos
    to_target[:, 2] = 0.0
    x, y, z, w = q.unbind(1)
    roll = torch.atan2(2 * (w * x + y * z), w * w - x * x - y * y + z * z)
    yaw = torch.atan2(2 * (w * z + x * y), w * w + x * x - y * y - z * z)
    up = quat_rotate(q, torch.tensor([[0.0, 0.0, 1.0]]).expand(n, 3))[:, 2]
    heading_vec = quat_rotate(q, torch.tensor([[1.0, 0.0, 0.0]]).expand(n, 3))
    heading = (heading_vec * to_target / torch.linalg.norm(to_target, dim=1, keepdim=True)).sum(1)
    angle = wrap(torch.atan2(to_target[:, 1], to_target[:, 0]) - yaw)
    lower = torch.as_tensor(sim.dof_lower_np)
    upper = torch.as_tensor(sim.dof_upper_np)
    dof_pos_scaled = (2 * dof[:, :, 0] - upper - lower) / (upper - lower)
    parts = [
        pos[:, 2:3],
        quat_rotate_inverse(q, lin),
        quat_rotate_inverse(q, ang) * task.angular_velocity_scale,
        yaw[:, None], roll[:, None], angle[:, None], up[:, None], heading[:, None],
        dof_pos_scaled,
        dof[:, :, 1] * task.dof_velocity_scale,
    ]
    if task.dof_force_scale:
        parts.append(sim.acquire_dof_force_tensor().view(n, a) * task.dof_force_scale)
    parts.append(sim.acquire_force_sensor_tensor().view(n, -1) * task.contact_force_scale)
    parts.append(actions.clamp(-1, 1))
    return torch.cat(parts, dim=1)


def reward(obs: torch.Tensor, actions: torch.Tensor, progress: torch.Tensor, task, gears) -> torch.Tensor:
    a = actions.clamp(-1, 1)
    n_dof = a.shape[1]
    up_proj, heading_proj = obs[:, 10], obs[:, 11]
    dps = obs[:, 12 : 12 + n_dof]
    dvs = obs[:, 12 + n_dof : 12 + 2 * n_dof]
    ratio = torch.as_tensor(gears / gears.max(), dtype=torch.float32)
    heading = torch.where(heading_proj > 0.8, torch.full_like(heading_proj, task.heading_weight),
                          task.heading_weight * heading_proj / 0.8)
    up = torch.where(up_proj > 0.93, task.up_weight, 0.0)
    electricity = (torch.abs(a * dvs) * ratio).sum(1)
    if task.scaled_limit_cost:
        excess = torch.abs(dps) - task.joint_limit_threshold
        at_limit = ((excess > 0) * excess / (1 - task.joint_limit_threshold) * ratio).sum(1)
    else:
        at_limit = (dps > task.joint_limit_threshold).float().sum(1)
    r = (progress + task.alive_reward + up + heading - task.actions_cost * (a * a).sum(1)
         - task.energy_cost * electricity - task.joints_at_limit_cost * at_limit)
    return torch.where(obs[:, 0] < task.termination_height, torch.full_like(r, task.death_cost), r)
