"""Videos: frames show the robot, clips decode to the frames written, and a missing renderer or
encoder names what to install. Drawn by Mesa's software EGL on a CPU-only machine."""

import json
import os
import sys

import numpy as np
import pytest
import torch

pytest.importorskip("av")
pytest.importorskip("PIL")


def _fixed_state(task: str, copies: int = 1, below_floor: bool = False) -> dict:
    from warpgym.native.robots import NativeRobot

    robot = NativeRobot(task, copies=copies)
    robot.reset(np.random.default_rng(0))
    state = robot.state()
    if below_floor:  # same camera (it follows x, y only), robot hidden under the opaque floor
        state["root_pose"][:, 2] = -50.0
    return state


def _clip(state: dict, steps: int) -> dict:
    """The state held for ``steps`` steps with the joints swinging, so no two frames are alike
    (a GIF writer may merge equal frames into one)."""
    clip = {k: np.repeat(v[None], steps, axis=0) for k, v in state.items()}
    clip["dof_pos"] = clip["dof_pos"] + 0.3 * np.sin(np.arange(steps))[:, None, None]
    return clip


@pytest.mark.parametrize("task", ["Ant", "Humanoid"])
def test_frames_have_the_stated_size_and_show_the_robot(task):
    from warpgym.media.robots import RobotRenderer

    robot, empty = _fixed_state(task), _fixed_state(task, below_floor=True)
    with RobotRenderer(task, width=160, height=120) as r:
        frames = [r.render(**robot) for _ in range(10)]
        blank = r.render(**empty)
    assert all(f.shape == (120, 160, 3) and f.dtype == np.uint8 for f in frames)
    assert all(np.array_equal(f, frames[0]) for f in frames)  # a fixed state draws the same picture
    changed = np.abs(frames[0].astype(int) - blank.astype(int)).sum(axis=2) > 30
    assert changed.mean() > 0.01, f"the robot covers {changed.mean():.4f} of the frame"
    rows, cols = np.nonzero(changed)  # ... and it is in the middle, where the camera looks
    assert 24 < rows.mean() < 100 and 40 < cols.mean() < 120


def test_a_grid_draws_every_robot():
    from warpgym.media.robots import RobotRenderer, grid_offsets

    offsets = grid_offsets(4, 2.5)
    assert len({tuple(o) for o in offsets}) == 4 and np.ptp(offsets[:, 1]) == 2.5
    state = _fixed_state("Ant", copies=4)
    with RobotRenderer("Ant", copies=4, width=160, height=120) as r:
        full = r.render(**state).astype(int)
        state["root_pose"][3, 2] = -50.0
        three = r.render(**state).astype(int)
    assert (np.abs(full - three).sum(axis=2) > 30).mean() > 0.003  # the fourth robot is drawn


def test_mp4_and_gif_decode_to_the_frames_written(tmp_path):
    import av
    from PIL import Image

    from warpgym.media.robots import render_clip

    mp4, gif = str(tmp_path / "a.mp4"), str(tmp_path / "a.gif")
    frames = render_clip("Ant", _clip(_fixed_state("Ant"), 10), {mp4: {"fps": 60}, gif: {"fps": 20, "width": 80}},
                         width=160, height=120)
    assert frames == {mp4: 10, gif: 4}  # 60 fps: every control step; 20 fps: every third
    with av.open(mp4) as c:
        decoded = [f.to_ndarray(format="rgb24") for f in c.decode(video=0)]
        assert c.streams.video[0].average_rate == 60
    assert len(decoded) == 10 and decoded[0].shape == (120, 160, 3)
    with Image.open(gif) as im:
        assert (im.n_frames, im.size, im.info["duration"]) == (4, (80, 60), 50)
    assert not [p for p in os.listdir(tmp_path) if ".tmp" in p]  # no temporary files left behind


def test_bad_video_settings_are_refused(tmp_path):
    from warpgym.media.render import check_size
    from warpgym.media.video import VideoWriter, frame_stride

    with pytest.raises(ValueError, match="must end in .mp4 or .gif"):
        VideoWriter(str(tmp_path / "a.avi"), 30)
    with pytest.raises(ValueError, match="must divide 60"):
        frame_stride(25)
    with pytest.raises(ValueError, match="must divide 100"):
        VideoWriter(str(tmp_path / "a.gif"), 30)
    with pytest.raises(ValueError, match="must be even"):
        check_size(641, 480)
    with pytest.raises(ValueError, match="no frames"):
        VideoWriter(str(tmp_path / "a.mp4"), 30).close()


def test_a_missing_encoder_or_renderer_names_what_to_install(tmp_path, monkeypatch):
    from warpgym.media import render
    from warpgym.media.video import VideoWriter

    monkeypatch.setitem(sys.modules, "av", None)  # as if PyAV were not installed
    with pytest.raises(ImportError, match=r"warpgym\[video\]"):
        VideoWriter(str(tmp_path / "a.mp4"), 30)
    monkeypatch.setitem(sys.modules, "mujoco.egl", None)
    monkeypatch.setitem(sys.modules, "mujoco.osmesa", None)
    with pytest.raises(render.RendererUnavailable, match="tried egl.*osmesa.*MUJOCO_GL=egl"):
        render.probe_renderer()


def test_a_view_closes_what_it_opened_once_and_leaves_no_exit_hook(monkeypatch):
    """ClosedAtExit: what a view opened is closed by its close() or at exit, once, and a closed view leaves no hook
    behind (a hook left holding a freed renderer would close it twice at exit)."""
    import atexit

    from warpgym.media.render import ClosedAtExit

    hooks = []
    monkeypatch.setattr(atexit, "register", hooks.append)
    monkeypatch.setattr(atexit, "unregister", hooks.remove)

    class Opened:
        closes = 0

        def close(self):
            self.closes += 1

    first, second = Opened(), Opened()
    view = ClosedAtExit()
    view.hold(first)
    view.hold(second)
    assert len(hooks) == 1  # one hook for all it holds
    hooks[0]()  # the exit hook alone closes both
    assert (first.closes, second.closes) == (1, 1)
    view.close()
    assert (first.closes, second.closes) == (1, 1) and hooks == []


def test_train_video_flag_fails_before_building_anything(monkeypatch, capsys):
    from warpgym.cli import train

    with pytest.raises(SystemExit):
        train.parse_args(["--video", "--no-eval"])
    assert "drop --no-eval" in capsys.readouterr().err
    monkeypatch.setitem(sys.modules, "av", None)
    with pytest.raises(SystemExit):
        train.parse_args(["--video"])
    assert 'pip install "warpgym[video]"' in capsys.readouterr().err


def test_evaluation_clip_is_drawn_off_the_training_process(ant_env, tmp_path):
    """The recorder copies states on the device during the evaluation; a separate process draws
    them into an MP4 and a TensorBoard GIF."""
    import torch
    from tensorboard.backend.event_processing.event_accumulator import EventAccumulator

    from agents.evaluate import evaluate
    from warpgym.media.clips import EvalVideoRecorder

    class Still:  # a policy that holds every joint at zero torque
        def act_deterministic(self, obs):
            return torch.zeros(obs.shape[0], ant_env.num_actions)

    rec = EvalVideoRecorder(str(tmp_path), steps=6, every=2, fps=30, width=96, height=64, copies=2)
    for evaluation in range(3):  # evaluations 0 and 2 are recorded
        evaluate(ant_env, Still(), lambda o: o, max_steps=11, recorder=rec)
        rec.finish(iteration=10 * evaluation, samples=1000 * evaluation)
    rec.close()
    videos = sorted(os.listdir(tmp_path / "videos"))
    assert [v for v in videos if v.endswith(".mp4")] == ["eval-000000.mp4", "eval-000020.mp4"], videos
    assert not [v for v in videos if v.endswith((".npz", ".gif"))]  # inputs and GIFs cleaned up
    import av

    with av.open(str(tmp_path / "videos" / "eval-000020.mp4")) as c:
        assert sum(1 for _ in c.decode(video=0)) == 3  # 6 steps at 60 Hz kept at 30 fps
    events = EventAccumulator(str(tmp_path / "tensorboard"), size_guidance={"images": 0})
    events.Reload()
    images = events.Images("eval/video")
    assert [i.step for i in images] == [0, 2000] and images[0].encoded_image_string[:6] == b"GIF89a"
    log = (tmp_path / "videos" / "render.log").read_text()
    assert [json.loads(line)["iteration"] for line in log.splitlines() if line.startswith("{")] == [0, 20]


def test_gym_make_renders_rgb_frames_of_the_robot_and_declares_it():
    import gymnasium as gym

    env = gym.make("warpgym/Ant-v0", render_mode="rgb_array", render_size=(160, 120))
    assert env.metadata["render_modes"] == ["rgb_array", "human"] and env.metadata["render_fps"] == 60
    env.reset(seed=0)
    first = env.render()
    for _ in range(30):
        env.step(env.action_space.sample())
    later = env.render()
    env.close()
    assert first.shape == (120, 160, 3) and first.dtype == np.uint8
    assert np.abs(first.astype(int) - later.astype(int)).sum(axis=2).__gt__(30).mean() > 0.005  # the robot moved


def test_gym_make_vec_renders_one_frame_per_robot_for_the_first_k():
    import gymnasium as gym

    envs = gym.make_vec("warpgym/Ant-v0", num_envs=3, device="cpu", render_mode="rgb_array", render_robots=2,
                        render_size=(160, 120))
    envs.reset(seed=0)
    for _ in range(20):
        envs.step(np.random.default_rng(0).uniform(-1, 1, (3, 8)).astype(np.float32))
    frames = envs.render()
    envs.close()
    assert isinstance(frames, tuple) and len(frames) == 2 and all(f.shape == (120, 160, 3) for f in frames)
    assert not np.array_equal(frames[0], frames[1])  # two robots, each in its own frame


def test_gymnasiums_record_video_writes_a_clip(tmp_path):
    import av
    import gymnasium as gym

    pytest.importorskip("moviepy")
    env = gym.wrappers.RecordVideo(gym.make("warpgym/Ant-v0", render_mode="rgb_array", render_size=(160, 120)),
                                   str(tmp_path), episode_trigger=lambda e: e == 0, video_length=24,
                                   disable_logger=True)
    env.reset(seed=0)
    for _ in range(30):
        env.step(env.action_space.sample())
    env.close()
    clips = list(tmp_path.glob("*.mp4"))
    assert len(clips) == 1
    with av.open(str(clips[0])) as c:
        frames = sum(1 for _ in c.decode(video=0))
        assert c.streams.video[0].average_rate == 60
    assert frames == 24


def test_human_rendering_without_a_display_fails_in_one_line(monkeypatch):
    import gymnasium as gym

    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(RuntimeError, match=r"render_mode='human' opens MuJoCo's viewer, which needs a display"):
        gym.make("warpgym/Ant-v0", render_mode="human")
    with pytest.raises(ValueError, match=r"render_mode='video': choose one of \['rgb_array', 'human'\]"):
        gym.make_vec("warpgym/Ant-v0", num_envs=2, device="cpu", render_mode="video")


def test_a_suite_clip_plays_in_real_time_and_follows_the_runner(tmp_path):
    """Gymnasium's camera stays where the robot started; a clip's camera follows its root body, and its
    frames keep the task's time (Hopper's 8 ms control step: every 6th step, 50 ms a frame)."""
    from PIL import Image

    from warpgym.media.suite import SuiteView, render_suite_clip
    from warpgym.media.video import real_time_strides
    from warpgym.tasks.suite import SUITE

    assert real_time_strides(0.008, 20, gif=True) == (6, 20, 50)
    assert real_time_strides(0.05, 20, gif=True) == (1, 20, 50) and real_time_strides(0.05, 60, gif=False) == (1, 20, None)
    hopper = SUITE["Hopper-v5"]
    steps = 60
    qpos = np.tile(np.array([0.0, 1.25, 0.0, 0.0, 0.0, 0.0]), (steps, 1, 1))
    qpos[:, 0, 0] = np.linspace(0.0, 6.0, steps)  # runs 6 m
    qpos[:, 0, 3] = 0.5 * np.sin(np.arange(steps))  # no two frames alike
    gif = str(tmp_path / "hopper.gif")
    assert render_suite_clip(hopper, {"dof_pos": qpos, "dof_vel": np.zeros((steps, 1, 6))}, {gif: {"fps": 20}},
                             0.008, 160, 120) == {gif: 10}
    with Image.open(gif) as im:
        shown_ms = 0
        for i in range(im.n_frames):
            im.seek(i)
            shown_ms += im.info["duration"]
    assert abs(shown_ms / 1000 - steps * 0.008) < 0.05  # 0.50 s shown for 0.48 s simulated

    far, hidden = qpos[-1], qpos[-1].copy()
    hidden[0, 1] = -50.0  # under the opaque floor: what the camera sees without the robot
    view = SuiteView(hopper, "rgb_array", 1, 160, 120, follow=True)
    seen, empty = (view.render(q, np.zeros((1, 6)))[0].astype(int) for q in (far, hidden))
    view.close()
    # 6 m from its start the robot is still in view (Gymnasium 1.4's own camera has lost it there; 1.2's
    # tracks the model's "track" camera, which follows too)
    assert (np.abs(seen - empty).sum(axis=2) > 30).mean() > 0.01


def test_a_clip_of_humanoid_standup_follows_it_as_it_walks_off(tmp_path):
    """HumanoidStandup has no forward speed, but a policy that stands up steps away from where it lay (the
    learning table's 10-minute policy left a fixed camera's frame by 6 s): its clips follow the torso."""
    import gymnasium as gym
    from PIL import Image

    from warpgym.media.suite import render_suite_clip
    from warpgym.tasks.suite import SUITE

    task = SUITE["HumanoidStandup-v5"]
    env = gym.make(task.name)
    start = env.unwrapped.init_qpos.copy()
    env.close()
    steps = 8
    last = {}
    for name, z in (("seen", start[2]), ("hidden", -50.0)):  # hidden: under the opaque floor
        qpos = np.tile(start, (steps, 1, 1))
        qpos[:, 0, 0] = np.linspace(0.0, 6.0, steps)  # 6 m from where it lay
        qpos[:, 0, 2] = z
        gif = str(tmp_path / f"{name}.gif")
        render_suite_clip(task, {"dof_pos": qpos, "dof_vel": np.zeros((steps, 1, start.size - 1))},
                          {gif: {"fps": 20}}, 0.015, 160, 120)
        with Image.open(gif) as im:
            im.seek(im.n_frames - 1)
            last[name] = np.asarray(im.convert("RGB")).astype(int)
    assert (np.abs(last["seen"] - last["hidden"]).sum(axis=2) > 30).mean() > 0.01


def test_a_recorder_keeps_the_world_it_is_given_and_play_refuses_a_world_it_cannot_draw(ant_env, capsys, tmp_path):
    from warpgym.cli import play
    from warpgym.media.clips import StateRecorder

    ant_env.reset(seed=0)
    recorder = StateRecorder(3, first=2)
    poses = []
    for _ in range(3):
        recorder.capture(ant_env)
        poses.append(ant_env.sim.root_pose[2].cpu().numpy().copy())
        ant_env.step(torch.rand(4, ant_env.num_actions, device=ant_env.device) * 2 - 1)
    assert np.array_equal(recorder.states()["root_pose"][:, 0], np.stack(poses))
    with pytest.raises(ValueError, match="envs 3 to 4 recorded, but the env has 4 robots"):
        StateRecorder(2, copies=2, first=3).capture(ant_env)
    checkpoint = tmp_path / "checkpoint.pt"
    checkpoint.write_bytes(b"")  # parse_args only checks that it is there
    for argv, says in ((["--world", "2"], "add --gif OUT.gif"), (["--world", "2", "--gif", "a.gif"], "--num-envs 3 or more")):
        with pytest.raises(SystemExit):
            play.parse_args([str(checkpoint), *argv])
        assert says in capsys.readouterr().err
