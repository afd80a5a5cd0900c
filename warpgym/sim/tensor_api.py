"""Isaac Gym's tensor functions as methods of ``Sim`` (same names, no ``sim`` argument).

Two kinds of tensors come out of here (docs/tensor_api.md has the table):
  * live views of Newton's own arrays (``dof_pos``, ``dof_vel``, ``root_pose``, ``root_vel``,
    ``body_q``, ``body_qd``, ``dof_actuation_force``): zero copy, always current, writable;
  * Isaac-layout buffers (``acquire_*``): allocated once, filled on the device by ``refresh_*``.
"""

from __future__ import annotations

import torch
import warp as wp

from kernels import tensor_api as k_api
from warpgym.sim.checks import check_env_ids, check_float_tensor


class TensorAPI:
    # Provided by Sim: num_envs, num_dofs, bodies_per_env, device, torch_device, state, solver,
    # joint_q, joint_qd, joint_f, newton_to_mj_dof, _order, check_inputs, warp_buffer(), ...

    # ------------------------------------------------------------------ live views
    @property
    def root_pose(self) -> torch.Tensor:
        """(N, 7) pos 3, quat xyzw 4 of each root; a view of Newton's ``joint_q``."""
        return self.to_torch(self.joint_q)[:, : k_api.ROOT_COORDS]

    @property
    def root_vel(self) -> torch.Tensor:
        """(N, 6) linear (root COM) and angular velocity, world frame; a view of ``joint_qd``."""
        return self.to_torch(self.joint_qd)[:, : k_api.ROOT_DOFS]

    @property
    def dof_pos(self) -> torch.Tensor:
        """(N, K) joint positions; a view of Newton's ``joint_q``."""
        return self.to_torch(self.joint_q)[:, k_api.ROOT_COORDS :]

    @property
    def dof_vel(self) -> torch.Tensor:
        """(N, K) joint velocities; a view of Newton's ``joint_qd``."""
        return self.to_torch(self.joint_qd)[:, k_api.ROOT_DOFS :]

    @property
    def dof_actuation_force(self) -> torch.Tensor:
        """(N, K) joint torques applied during the next step; a view of Newton's ``control.joint_f``."""
        return self.to_torch(self.joint_f)[:, k_api.ROOT_DOFS :]

    @property
    def body_q(self) -> torch.Tensor:
        """(N, B, 7) body frame pos 3, quat xyzw 4 (world); a view of Newton's ``body_q``, set by each step."""
        return self.to_torch(self.state.body_q).view(self.num_envs, self.bodies_per_env, 7)

    @property
    def body_qd(self) -> torch.Tensor:
        """(N, B, 6) COM linear and angular velocity (world); a view of Newton's ``body_qd``."""
        return self.to_torch(self.state.body_qd).view(self.num_envs, self.bodies_per_env, 6)

    # ------------------------------------------------------------------ device passes (capturable)
    def _run(self, fn) -> None:
        self.launch(None, fn)

    def contact_wrench_buffer(self) -> wp.array:
        """(N*B, 6) per-body contact force 3 and torque 3 about the body origin, world frame."""
        return self.warp_buffer("contact_wrench", (self.num_envs * self.bodies_per_env, 6))[0]

    def compute_contact_wrenches(self) -> None:
        d, m = self.solver.mjw_data, self.solver.mjw_model
        wp.launch(
            k_api.contact_wrenches_from_mujoco,
            dim=d.cfrc_ext.shape,
            inputs=[d.cfrc_ext, d.xpos, d.subtree_com, m.body_rootid, self.solver.mjc_body_to_newton],
            outputs=[self.contact_wrench_buffer()],
            device=self.device,
        )

    def dof_force_buffer(self) -> wp.array:
        """(N, K) generalised force on each joint: actuation plus passive spring and damping."""
        return self.warp_buffer("dof_force", (self.num_envs, self.num_dofs))[0]

    def compute_dof_forces(self) -> None:
        d = self.solver.mjw_data
        wp.launch(
            k_api.dof_forces_from_mujoco,
            dim=(self.num_envs, self.num_dofs),
            inputs=[d.qfrc_applied, d.qfrc_passive, self.newton_to_mj_dof],
            outputs=[self.dof_force_buffer()],
            device=self.device,
        )

    # ------------------------------------------------------------------ Isaac-layout buffers
    def acquire_actor_root_state_tensor(self) -> torch.Tensor:
        """(N, 13): pos 3, quat xyzw 4, lin vel 3, ang vel 3, world frame. Refresh to update."""
        self.warp_buffer("root_state", (self.num_envs, 13))
        self.refresh_actor_root_state_tensor()
        return self._tensors["root_state"][1]

    def refresh_actor_root_state_tensor(self) -> None:
        out = self.warp_buffer("root_state", (self.num_envs, 13))[0]
        self._run(lambda: wp.launch(k_api.pack_root_state, dim=self.num_envs,
                                    inputs=[self.joint_q, self.joint_qd], outputs=[out], device=self.device))

    def acquire_dof_state_tensor(self) -> torch.Tensor:
        """(N*K, 2): position, velocity of every joint, env-major. Refresh to update."""
        self.warp_buffer("dof_state", (self.num_envs * self.num_dofs, 2))
        self.refresh_dof_state_tensor()
        return self._tensors["dof_state"][1]

    def refresh_dof_state_tensor(self) -> None:
        out = self.warp_buffer("dof_state", (self.num_envs * self.num_dofs, 2))[0]
        self._run(lambda: wp.launch(k_api.pack_dof_state, dim=(self.num_envs, self.num_dofs),
                                    inputs=[self.joint_q, self.joint_qd], outputs=[out], device=self.device))

    def acquire_rigid_body_state_tensor(self) -> torch.Tensor:
        """(N*B, 13): body frame pos 3, quat xyzw 4, COM lin vel 3, ang vel 3, world frame."""
        self.warp_buffer("body_state", (self.num_envs * self.bodies_per_env, 13))
        self.refresh_rigid_body_state_tensor()
        return self._tensors["body_state"][1]

    def refresh_rigid_body_state_tensor(self) -> None:
        out = self.warp_buffer("body_state", (self.num_envs * self.bodies_per_env, 13))[0]
        self._run(lambda: wp.launch(k_api.pack_rigid_body_state, dim=self.num_envs * self.bodies_per_env,
                                    inputs=[self.state.body_q, self.state.body_qd], outputs=[out],
                                    device=self.device))

    def acquire_net_contact_force_tensor(self) -> torch.Tensor:
        """(N*B, 3): net contact force on each body, world frame, from the last substep."""
        self.enable_contact_forces()
        self.refresh_net_contact_force_tensor()
        return self._tensors["contact_wrench"][1][:, :3]

    def refresh_net_contact_force_tensor(self) -> None:
        self._run(self.compute_contact_wrenches)

    def acquire_force_sensor_tensor(self) -> torch.Tensor:
        """(N*F, 6): contact force 3 and torque 3 (about the body origin, world frame) on each foot.

        The sensors sit on the robot's feet (``spec.feet``, in that order), as IsaacGymEnvs places
        force sensors on the Ant's and Humanoid's feet.
        """
        self.enable_contact_forces()
        self.refresh_force_sensor_tensor()
        return self._tensors["force_sensors"][1]

    def refresh_force_sensor_tensor(self) -> None:
        feet = self.foot_bodies
        out = self.warp_buffer("force_sensors", (self.num_envs * feet.shape[0], 6))[0]

        def run():
            self.compute_contact_wrenches()
            wp.launch(k_api.gather_force_sensors, dim=(self.num_envs, feet.shape[0]),
                      inputs=[self.contact_wrench_buffer(), feet, self.bodies_per_env], outputs=[out],
                      device=self.device)

        self._run(run)

    def acquire_dof_force_tensor(self) -> torch.Tensor:
        """(N*K,): generalised force on each joint (actuation + passive), from the last substep."""
        self.refresh_dof_force_tensor()
        return self._tensors["dof_force"][1].view(-1)

    def refresh_dof_force_tensor(self) -> None:
        self._run(self.compute_dof_forces)

    # ------------------------------------------------------------------ setters
    def set_dof_actuation_force_tensor(self, forces: torch.Tensor) -> None:
        """Joint torques for the next steps, (N*K,) or (N, K) float32 on the sim's device."""
        n, k = self.num_envs, self.num_dofs
        forces = check_float_tensor("forces", forces, self.torch_device, [(n * k,), (n, k)]).view(n, k)
        self._run(lambda: wp.launch(k_api.scatter_dof_forces, dim=(n, k), inputs=[wp.from_torch(forces)],
                                    outputs=[self.joint_f], device=self.device))

    def set_actor_root_state_tensor_indexed(self, states: torch.Tensor, env_ids: torch.Tensor) -> None:
        """Write rows ``env_ids`` of ``states`` (N, 13) into the roots of those envs."""
        states = check_float_tensor("states", states, self.torch_device, [(self.num_envs, 13)])
        ids = self._env_ids(env_ids)
        wp_ids = wp.from_torch(ids)

        def scatter():
            wp.launch(k_api.scatter_root_state_indexed, dim=ids.shape[0], inputs=[wp.from_torch(states), wp_ids],
                      outputs=[self.joint_q, self.joint_qd], device=self.device)
            self.clear_warm_start(wp_ids)

        self._run(scatter)

    def set_dof_state_tensor_indexed(self, states: torch.Tensor, env_ids: torch.Tensor) -> None:
        """Write the dof rows of envs ``env_ids`` from ``states`` (N*K, 2) into their joints."""
        states = check_float_tensor("states", states, self.torch_device, [(self.num_envs * self.num_dofs, 2)])
        ids = self._env_ids(env_ids)
        wp_ids = wp.from_torch(ids)

        def scatter():
            wp.launch(k_api.scatter_dof_state_indexed, dim=(ids.shape[0], self.num_dofs),
                      inputs=[wp.from_torch(states), wp_ids], outputs=[self.joint_q, self.joint_qd],
                      device=self.device)
            self.clear_warm_start(wp_ids)

        self._run(scatter)

    def _env_ids(self, env_ids) -> torch.Tensor:
        return check_env_ids("env_ids", env_ids, self.torch_device, self.num_envs, self.check_inputs)
