"""Headless rendering: frame shape, drawing to scale, human mode, RecordVideo, vector frames."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")

import gymnasium as gym
import numpy as np
import pytest

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)
from amigo_gym.envs import AmigoBotEnv, AmigoBotVectorEnv

pytest.importorskip("pygame")

WHITE = (255, 255, 255)


def pixel(frame: np.ndarray, x: float, y: float) -> tuple[int, ...]:
    """Colour at world point (x, y) [m] for the default task's view.

    Independent closed form of the documented view: the circle (centre (0, 1), R = 1) spans
    [-1, 1] x [0, 2]; the margin is termination_distance + 0.25 = 0.5 m; the square window is
    therefore [-1.5, 1.5] x [-0.5, 2.5] on 600 px: 200 px/m, y up.
    """
    u = (x + 1.5) * 200.0
    v = 600.0 - (y + 0.5) * 200.0
    return tuple(int(c) for c in frame[int(v), int(u)])


def test_rgb_array_frame_to_scale() -> None:
    env = AmigoBotEnv(render_mode="rgb_array")
    env.reset(options={"pose": (0.5, 1.0, 0.0)})  # A at (0.5, 1), heading +x
    frame = env.render()
    assert isinstance(frame, np.ndarray) and frame.shape == (600, 600, 3) and frame.dtype == np.uint8
    # H, l3 = 0.08 m ahead of A: red
    r, g, b = pixel(frame, 0.58, 1.0)
    assert r > 180 and g < 80 and b < 80
    # body 0.330 m long and 0.279 m wide, centred on A: inside near its corners, outside beyond
    body = pixel(frame, 0.65, 1.05)
    assert body != WHITE and body[0] == body[1]  # the grey body fill
    assert pixel(frame, 0.69, 1.05) == WHITE  # 0.19 m ahead of A: beyond the half length 0.165
    assert pixel(frame, 0.60, 1.16) == WHITE  # 0.16 m to the left: beyond the half width 0.1395
    assert pixel(frame, 0.60, 1.12) == body
    # wheel 1 (right) at K = A + l1 (sin b, -cos b) = (0.5, 0.88), wheel 2 (left) at (0.5, 1.12): dark
    assert max(pixel(frame, 0.47, 0.88)) < 60 and max(pixel(frame, 0.47, 1.12)) < 60
    # castor disc of radius r3 = 0.03 m at l5 = 0.12 m behind A
    assert max(pixel(frame, 0.38, 1.0)) < 120 and pixel(frame, 0.38, 1.0) != body


def test_trail_and_frames_change() -> None:
    env = gym.make("AmigoBot-v0", render_mode="rgb_array")
    env.reset(seed=0)
    f0 = env.render()
    for _ in range(20):
        env.step(np.array([0.3, 0.25]))
    f1 = env.render()
    assert isinstance(f0, np.ndarray) and isinstance(f1, np.ndarray) and not np.array_equal(f0, f1)
    env.close()


def test_human_mode_headless() -> None:
    env = gym.make("AmigoBot-v0", render_mode="human", dt=0.02)
    env.reset(seed=0)
    for _ in range(3):
        env.step(np.array([0.3, 0.25]))
    assert env.render() is None
    env.close()


def test_render_without_mode_warns() -> None:
    env = AmigoBotEnv()
    env.reset(seed=0)
    with pytest.warns(UserWarning, match="render_mode"):
        assert env.render() is None


def test_record_video(tmp_path: Path) -> None:
    pytest.importorskip("moviepy")
    from gymnasium.wrappers import RecordVideo

    env = RecordVideo(
        gym.make("AmigoBot-v0", render_mode="rgb_array", max_episode_steps=15),
        str(tmp_path / "videos"),
        episode_trigger=lambda e: True,
        disable_logger=True,
    )
    env.reset(seed=0)
    done = False
    while not done:
        _, _, term, trunc, _ = env.step(np.array([0.3, 0.25]))
        done = term or trunc
    env.close()  # type: ignore[no-untyped-call]
    videos = list((tmp_path / "videos").glob("*.mp4"))
    assert len(videos) == 1 and videos[0].stat().st_size > 1000


def test_vector_env_frames() -> None:
    envs = AmigoBotVectorEnv(num_envs=2, render_mode="rgb_array")
    envs.reset(seed=0)
    envs.step(np.full((2, 2), 0.3))
    frames: Any = envs.render()
    assert isinstance(frames, tuple) and len(frames) == 2
    assert all(f.shape == (600, 600, 3) and f.dtype == np.uint8 for f in frames)
    assert not np.array_equal(frames[0], frames[1])  # different seeded starts
    envs.close()
