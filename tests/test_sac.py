"""The off-policy learner (agents.sac): the projection, the n-step replay and the goal relabelling against
hand-computed cases, learning on the point mass against a number, checkpoints, and its errors."""

from __future__ import annotations

import pytest
import torch

from agents.checkpoint import load, policy_from_checkpoint
from agents.export import deployable
from agents.sac import OffPolicyRunner, ReplayBuffer, SACConfig, goal_spec, project, relabel
from point_mass import PointMassVecEnv

# a small learner for the point mass: two critic steps and one actor step an env step
SMALL = dict(actor_dims=(64, 64), critic_dims=(64, 64), batch_size=256, num_updates=2, policy_frequency=1,
             buffer_size=2000, v_min=-60.0, v_max=10.0, gamma=0.95, num_atoms=51, learning_starts=20,
             steps_per_iteration=25, alpha_init=0.01, target_entropy_ratio=1.0, eval_gap=0.0)


# ---------------------------------------------------------------------------------------------- projection
def test_projection_moves_mass_as_computed_by_hand():
    support = torch.linspace(-2.0, 2.0, 5)  # atoms at -2, -1, 0, 1, 2
    probs = torch.tensor([[0.0, 0.0, 1.0, 0.0, 0.0],  # all at 0
                          [0.0, 0.0, 1.0, 0.0, 0.0],
                          [0.0, 0.5, 0.5, 0.0, 0.0],
                          [0.2, 0.2, 0.2, 0.2, 0.2]])
    reward = torch.tensor([1.0, 0.25, 0.0, 5.0])
    discount = torch.tensor([1.0, 1.0, 0.5, 0.0])
    out = project(probs, reward, discount, support)
    # a shift by one atom: the mass moves to 1
    assert torch.allclose(out[0], torch.tensor([0.0, 0.0, 0.0, 1.0, 0.0]))
    # a shift by a quarter spacing: 3/4 stays at 0, 1/4 goes to 1
    assert torch.allclose(out[1], torch.tensor([0.0, 0.0, 0.75, 0.25, 0.0]))
    # halved: -1 lands on -0.5 (half to -1, half to 0), 0 stays
    assert torch.allclose(out[2], torch.tensor([0.0, 0.25, 0.75, 0.0, 0.0]))
    # no bootstrap and a reward beyond the support: everything at its top atom
    assert torch.allclose(out[3], torch.tensor([0.0, 0.0, 0.0, 0.0, 1.0]))
    assert torch.allclose(out.sum(1), torch.ones(4))


def test_projection_keeps_the_mean_inside_the_support():
    torch.manual_seed(0)
    support = torch.linspace(-10.0, 10.0, 51)
    probs = torch.rand(64, 51).softmax(1)
    reward, discount = torch.rand(64) - 0.5, torch.full((64,), 0.9)
    out = project(probs, reward, discount, support)
    # the projection is linear between atoms, so the mean of a distribution that stays inside the support is exact
    assert torch.allclose((out * support).sum(1), reward + discount * (probs * support).sum(1), atol=1e-5)


# ---------------------------------------------------------------------------------------------- replay
def _filled_buffer(capacity=8, steps=6):
    """One env; rewards 1, 2, 3, ...; the episode ends after the third step (terminated) and the sixth (cut by the
    time limit); the observation is the step's number, the next one that number + 0.5."""
    buffer = ReplayBuffer(capacity, 1, 1, 1, torch.device("cpu"), goal_size=1)
    for t in range(steps):
        ended = t in (2, 5)
        buffer.add(torch.tensor([[float(t)]]), torch.zeros(1, 1), torch.tensor([t + 1.0]), torch.tensor([[t + 0.5]]),
                   torch.tensor([t == 2]), torch.tensor([ended]), achieved=torch.tensor([[10.0 * t]]))
    return buffer


def _at(buffer, age):
    """Uniform draws that pick the held step of this age (0: the oldest) of env 0."""
    return torch.tensor([[0.0, (age + 0.5) / int(buffer.size)]])


def test_n_step_returns_stop_at_the_episode_end_and_the_newest_step():
    buffer, g = _filled_buffer(), 0.5
    one = buffer.sample(1, n_step=3, gamma=g, uniform=_at(buffer, 0))  # steps 0, 1, 2; 2 terminated
    assert one["reward"].item() == pytest.approx(1 + g * 2 + g * g * 3)
    assert one["next_obs"].item() == 2.5 and one["discount"].item() == 0.0 and one["steps"].item() == 3
    two = buffer.sample(1, n_step=3, gamma=g, uniform=_at(buffer, 1))  # steps 1, 2: the episode ends at 2
    assert two["reward"].item() == pytest.approx(2 + g * 3) and two["steps"].item() == 2
    three = buffer.sample(1, n_step=3, gamma=g, uniform=_at(buffer, 3))  # steps 3, 4, 5: cut, bootstrapped
    assert three["reward"].item() == pytest.approx(4 + g * 5 + g * g * 6)
    assert three["next_obs"].item() == 5.5 and three["discount"].item() == pytest.approx(g ** 3)
    newest = buffer.sample(1, n_step=3, gamma=g, uniform=_at(buffer, 5))  # the newest step: one step only
    assert newest["steps"].item() == 1 and newest["discount"].item() == pytest.approx(g)


def test_the_ring_overwrites_the_oldest_steps():
    buffer = _filled_buffer(capacity=4, steps=6)  # holds steps 2..5
    assert int(buffer.size) == 4
    oldest = buffer.sample(1, n_step=1, uniform=_at(buffer, 0))
    assert oldest["obs"].item() == 2.0 and oldest["reward"].item() == 3.0


# ---------------------------------------------------------------------------------------------- relabelling
class _GoalEnv:
    """The goal layout of an env whose observation is (position, goal); the reward is 0 within 1 of the goal, -1
    beyond (Fetch's sparse reward)."""

    goal_layout = {"obs": (1, 2)}

    @staticmethod
    def compute_reward(achieved, desired, info):
        return -(torch.linalg.norm(achieved - desired, dim=-1) > 1.0).float()


def test_relabelling_takes_a_goal_the_episode_reached_later():
    buffer = ReplayBuffer(8, 1, 2, 1, torch.device("cpu"), goal_size=1)
    for t in range(6):  # episodes of steps 0-2 and 3-5; the goal 99 is never reached
        buffer.add(torch.tensor([[float(t), 99.0]]), torch.zeros(1, 1), torch.tensor([-1.0]),
                   torch.tensor([[t + 0.5, 99.0]]), torch.tensor([False]), torch.tensor([t in (2, 5)]),
                   achieved=torch.tensor([[10.0 * t]]))
    spec = goal_spec(_GoalEnv(), max_episode_steps=3)
    batch = buffer.sample(2, uniform=torch.tensor([[0.0, 0.5 / 6], [0.0, 1.5 / 6]]))  # steps 0 and 1
    # step 0: the future pick 0.7 of its 3 steps is step 2 (achieved 20); step 1: 0.1 of its 2 steps is step 1 itself
    out = relabel(batch, buffer, spec, fraction=0.8, uniform=torch.tensor([[0.7, 0.5], [0.1, 0.5]]))
    assert out["obs"][:, 1].tolist() == [20.0, 10.0] and out["next_obs"][:, 1].tolist() == [20.0, 10.0]
    assert out["obs"][:, 0].tolist() == [0.0, 1.0]  # the position is untouched
    # step 0 achieved 0, 20 away from its new goal: -1; step 1 achieved its own goal: 0
    assert out["reward"].tolist() == [-1.0, 0.0]
    kept = relabel(buffer.sample(1, uniform=torch.tensor([[0.0, 0.5 / 6]])), buffer, spec, fraction=0.8,
                   uniform=torch.tensor([[0.7, 0.9]]))  # 0.9 >= 0.8: not relabelled
    assert kept["obs"][0, 1].item() == 99.0 and kept["reward"].item() == -1.0 and not kept["relabelled"].item()


def test_a_goal_layout_without_compute_reward_is_refused():
    class NoReward:
        goal_layout = {"obs": (0, 2)}

    with pytest.raises(TypeError, match="compute_reward"):
        goal_spec(NoReward(), 50)


# ---------------------------------------------------------------------------------------------- learning
@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    """SAC on the point mass for 60 iterations of 25 steps (3,000 critic steps); its history and run directory."""
    torch.set_num_threads(2)
    run_dir = str(tmp_path_factory.mktemp("sac"))
    runner = OffPolicyRunner(PointMassVecEnv(32, seed=0), SACConfig(**SMALL, save_gap=20, seed=0),
                             run_dir=run_dir, eval_env=PointMassVecEnv(16, seed=1), print_fn=lambda s: None)
    start = runner.evaluate()["eval/return"]
    history = runner.learn(max_iterations=60)
    runner.close()
    return start, history, run_dir


def test_sac_learns_the_point_mass(trained):
    start, history, _ = trained
    # the untrained policy (zero actions) scores about -60 on these starts; one that brakes at the origin about -15
    # halfway between the untrained policy and one that stops at the origin: seeds vary by a few points
    best = max(r["eval/return"] for r in history[-10:])
    assert start < -50
    assert best > -30, [round(r["eval/return"], 1) for r in history]
    assert history[-1]["sac/critic_loss"] > 0 and 0 < history[-1]["sac/alpha"] < 1


def test_a_sac_checkpoint_plays_exports_and_resumes(trained, tmp_path):
    _, history, run_dir = trained
    ckpt = load(f"{run_dir}/checkpoint.pt", torch.device("cpu"))
    assert ckpt["config"]["agent"] == "AgentSAC" and ckpt["iteration"] == 60
    policy, normalize = policy_from_checkpoint(ckpt, 4, 2, torch.device("cpu"))
    obs = torch.randn(5, 4)
    with torch.no_grad():
        acts = policy.act_deterministic(normalize(obs))
        assert torch.allclose(deployable(ckpt)(obs), acts, atol=1e-6)  # export writes what evaluation plays
    assert acts.abs().max() < 1
    resumed = OffPolicyRunner(PointMassVecEnv(32, seed=0), SACConfig(**SMALL, save_gap=20, seed=0), run_dir=run_dir,
                              eval_env=PointMassVecEnv(16, seed=1), print_fn=lambda s: None)
    resumed.load(f"{run_dir}/checkpoint.pt")
    assert resumed.iteration == 60 and resumed.samples == history[-1]["samples"]
    assert torch.equal(resumed.sac.log_alpha.detach(), ckpt["log_alpha"])
    with torch.no_grad():  # its weights and its normaliser are the checkpoint's
        assert torch.allclose(resumed.policy.act_deterministic(resumed.normalize(obs)), acts)
    more = resumed.learn(max_iterations=62)  # refills learning_starts steps, then updates again
    assert [r["iteration"] for r in more] == [61, 62] and more[-1]["sac/critic_loss"] > 0


def test_an_asymmetric_critic_keeps_its_own_observations_and_learns_the_position():
    """The policy sees the velocity alone, the critic the position too (tests/test_asymmetric.py's env): the replay
    keeps the critic's true next observation across an episode's end, and the trained critic values a mass at rest
    at the origin above one at rest 2.8 m out, which it could not through the velocity."""
    from test_asymmetric import HiddenPositionMass  # noqa: PLC0415

    env = HiddenPositionMass(16)
    runner = OffPolicyRunner(env, SACConfig(**{**SMALL, "learning_starts": 10**6}), print_fn=lambda s: None)
    runner.learn(max_iterations=3)  # 75 steps, no update: the episodes end after step 50
    b = runner.buffer
    assert b.critic_obs.shape == (SMALL["buffer_size"], 16, 4) and b.obs.shape[-1] == 2
    assert torch.equal(b.next_critic_obs[:48], b.critic_obs[1:49])  # within the episode, the next is the next
    assert b.ended[49].all() and not torch.equal(b.next_critic_obs[49], b.critic_obs[50])  # across its end, not
    assert (b.critic_obs[50][:, 2:] == 0).all()  # the new episode starts at rest
    trained = OffPolicyRunner(HiddenPositionMass(32), SACConfig(**SMALL), print_fn=lambda s: None)
    trained.learn(max_iterations=20)
    states = torch.tensor([[0.0, 0.0, 0.0, 0.0], [2.0, 2.0, 0.0, 0.0]])
    with torch.no_grad():
        q = trained.critic.values(trained.critic(trained.normalize_critic(states), torch.zeros(2, 2))).mean(0)
    assert q[0] - q[1] > 5.0, q.tolist()


# ---------------------------------------------------------------------------------------------- errors
@pytest.mark.parametrize("change, words", [
    (dict(num_updates=8, policy_frequency=3), "policy_frequency=3 does not divide num_updates=8"),
    (dict(v_min=5.0, v_max=-5.0), "v_min < v_max"),
    (dict(actor_dims=()), "actor_dims=()"),
    (dict(relabel_fraction=1.5), "relabel_fraction=1.5"),
    (dict(buffer_size=3, n_step=3), "buffer_size=3 must exceed n_step=3"),
])
def test_bad_settings_name_the_value(change, words):
    with pytest.raises(ValueError, match=words.replace("(", r"\(").replace(")", r"\)")):
        SACConfig(**change).validated()


def test_goal_relabelling_refuses_n_step_returns():
    class GoalMass(PointMassVecEnv):
        goal_layout = {"obs": (0, 2)}

        def compute_reward(self, achieved, desired, info):
            return -torch.linalg.norm(achieved - desired, dim=-1)

    with pytest.raises(ValueError, match="n_step=3"):
        OffPolicyRunner(GoalMass(4), SACConfig(**{**SMALL, "n_step": 3}), print_fn=lambda s: None)


# ---------------------------------------------------------------------------------------------- the command line
def _sac_fields():
    from dataclasses import fields  # noqa: PLC0415

    from warpgym.cli.train_args import NOT_CONFIGURABLE  # noqa: PLC0415

    # a negative bound of the support or of the log-std is a value that works
    signed = ("v_min", "v_max", "log_std_min", "log_std_max")
    return [f for f in fields(SACConfig) if f.name not in NOT_CONFIGURABLE + signed]


@pytest.mark.parametrize("field", _sac_fields(), ids=[f.name for f in _sac_fields()])
def test_a_wrong_sac_setting_is_refused_before_anything_is_built(field, capsys):
    from test_flags import refused, wrong_setting  # noqa: PLC0415

    from warpgym.cli import train_args  # noqa: PLC0415

    value = wrong_setting(field)
    value = "x,y" if field.name in ("actor_dims", "critic_dims") else value
    line = refused(train_args.parse_args, ["--algo", "sac", "--config", f"{field.name}={value}"], capsys)
    assert line.startswith("warpgym train: error: --config: ") and field.name in line


@pytest.mark.parametrize("argv, says", [
    (["--algo", "sac", "--horizon-len", "8"], "--horizon-len: PPO's settings; --algo sac takes its own"),
    (["--algo", "sac", "--overlap"], "--overlap: PPO's settings"),
    (["--algo", "sac", "--no-rollout-graph"], "--rollout-graph: PPO's settings"),
    (["--config", "num_updates=2"], "'num_updates' is not a PPO setting"),
    (["--algo", "sac", "--config", "net_dims=64"], "'net_dims' is not a SAC setting"),
])
def test_the_learners_flags_stay_with_their_learner(argv, says, capsys):
    from test_flags import refused  # noqa: PLC0415

    from warpgym.cli import train_args  # noqa: PLC0415

    assert says in refused(train_args.parse_args, argv, capsys)


def test_sac_takes_the_tasks_preset_and_the_flags(tmp_path):
    from warpgym.cli import train_args  # noqa: PLC0415
    from warpgym.cli.run_setup import build_config  # noqa: PLC0415
    from warpgym.tasks.presets import SAC_LEGGED  # noqa: PLC0415

    args = train_args.parse_args(["--task", "Go1VelocityFlat-v0", "--algo", "sac", "--config", "batch_size=4096",
                                  "--eval-gap", "5", "--target", "eval/return=10"])
    cfg = build_config(args, args.task, 64, "cpu")
    assert isinstance(cfg, SACConfig) and cfg.batch_size == 4096 and cfg.eval_gap == 5.0
    assert cfg.v_max == SAC_LEGGED["v_max"] and cfg.gamma == SAC_LEGGED["gamma"] and cfg.target == "eval/return=10"
    assert cfg.env_args["num_envs"] == 64 and cfg.eval_envs == 4  # on the CPU, few evaluation envs
