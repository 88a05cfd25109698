"""The native vector env (the compiled step) against gymnasium's SyncVectorEnv of the single env (the numpy
reference), within the golden tolerance (tests/golden_compare.py: 1e-9; float32 observations two roundings)."""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode, SyncVectorEnv

import amigo_gym  # noqa: F401  (registers AmigoBot-v0)
from amigo_gym.envs import AmigoBotVectorEnv

# settings that force terminations (large start noise, small termination distance) and truncations
HARD: dict[str, Any] = {"init_position_noise": 0.1, "termination_distance": 0.2, "max_episode_steps": 25}


def assert_identical(a: Any, b: Any, where: str = "") -> None:
    """Equal keys, dtypes and shapes, floats within the tolerance, the rest exactly (object arrays element by
    element)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), (where, set(a) ^ set(b))
        for k in a:
            assert_identical(a[k], b[k], f"{where}/{k}")
        return
    if isinstance(a, tuple):
        assert isinstance(b, tuple) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            assert_identical(x, y, f"{where}[{i}]")
        return
    a, b = np.asarray(a), np.asarray(b)
    assert a.dtype == b.dtype and a.shape == b.shape, (where, a.dtype, b.dtype, a.shape, b.shape)
    if a.dtype == object:
        for x, y in zip(a, b, strict=True):
            assert (x is None) == (y is None), where
            if x is not None:
                assert_identical(x, y, where)
    elif a.dtype.kind == "f":
        tol = 2.5e-7 if a.dtype == np.float32 else 1e-9
        np.testing.assert_allclose(a, b, rtol=tol, atol=tol, err_msg=where, strict=True)
    else:
        np.testing.assert_array_equal(a, b, err_msg=where, strict=True)


def make_pair(n: int, mode: AutoresetMode, **kw: Any) -> tuple[gym.vector.VectorEnv[Any, Any, Any], SyncVectorEnv]:
    vec = gym.make_vec("AmigoBot-v0", num_envs=n, vectorization_mode="vector_entry_point", autoreset_mode=mode, **kw)
    # the reference: single envs on the numpy float path (the native env runs its default, the compiled step)
    sync = gym.make_vec(
        "AmigoBot-v0",
        num_envs=n,
        vectorization_mode="sync",
        vector_kwargs={"autoreset_mode": mode},
        **{**kw, "kernel": "numpy"},
    )
    assert isinstance(vec.unwrapped, AmigoBotVectorEnv) and isinstance(sync, SyncVectorEnv)
    return vec, sync


@pytest.mark.parametrize("mode", [AutoresetMode.NEXT_STEP, AutoresetMode.SAME_STEP])
@pytest.mark.parametrize("seed", [0, 7, 123])
def test_vector_equals_sync(mode: AutoresetMode, seed: int) -> None:
    n = 6
    vec, sync = make_pair(n, mode, **HARD)
    assert vec.metadata["autoreset_mode"] == mode
    assert_identical(vec.reset(seed=seed), sync.reset(seed=seed), "reset")
    rng = np.random.default_rng(seed)
    ends = np.zeros(2, dtype=int)
    for t in range(90):
        a = rng.uniform(-0.3, 1.0, (n, 2))
        if t % 3 == 0:
            a = a.astype(np.float32)
        rv, rs = vec.step(a), sync.step(a)
        for name, x, y in zip(("obs", "reward", "terminated", "truncated", "info"), rv, rs, strict=True):
            assert_identical(x, y, f"step {t} {name}")
        ends += [int(rv[2].sum()), int(rv[3].sum())]
    assert ends[0] >= 3 and ends[1] >= 3, f"too few terminations/truncations to test autoreset: {ends}"
    # a later reset without seed continues every sub-env's generator identically
    assert_identical(vec.reset(), sync.reset(), "reset (no seed)")


def test_vector_equals_sync_seed_list_pose_option_and_reset_mask() -> None:
    n = 4
    vec, sync = make_pair(n, AutoresetMode.DISABLED, **HARD)
    seeds: list[int | None] = [3, 1, 4, 1]
    assert_identical(vec.reset(seed=seeds), sync.reset(seed=seeds))  # type: ignore[arg-type]
    pose = (-0.08, 0.01, 0.05)
    assert_identical(vec.reset(options={"pose": pose}), sync.reset(options={"pose": pose}))
    rng = np.random.default_rng(2)
    for t in range(60):
        a = rng.uniform(-0.2, 1.0, (n, 2))
        rv, rs = vec.step(a), sync.step(a)
        assert_identical(rv, rs, f"step {t}")
        done = rv[2] | rv[3]
        if done.any():  # Disabled mode: the user resets the finished ones
            assert_identical(
                vec.reset(options={"reset_mask": done.copy()}), sync.reset(options={"reset_mask": done.copy()})
            )


def test_make_vec_default_is_native_with_registration_limit() -> None:
    envs = gym.make_vec("AmigoBot-v0", num_envs=3)
    u = envs.unwrapped
    assert isinstance(u, AmigoBotVectorEnv)
    assert u.max_episode_steps == 400
    assert u.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
    assert envs.action_space.shape == (3, 2) and envs.observation_space.shape == (3, 10)
    u9 = gym.make_vec("AmigoBot-v0", num_envs=2, max_episode_steps=9, dt=0.2).unwrapped
    assert isinstance(u9, AmigoBotVectorEnv) and u9.max_episode_steps == 9 and u9.params.dt == 0.2


def test_truncation_every_max_steps_and_next_step_reset() -> None:
    envs = AmigoBotVectorEnv(num_envs=2, max_episode_steps=5, init_position_noise=0.0, init_heading_noise=0.0)
    envs.reset(seed=0)
    # steady wheel rates for R = 1, v = 0.2 (closed form); from the noise-free start H stays near the path
    ra = math.sqrt(1.0 - 0.08**2)
    bd = 0.2 / ra
    a = np.tile(np.array([(0.2 + 0.12 * bd) / 0.05, (0.2 - 0.12 * bd) / 0.05]) / 15.0, (2, 1))
    truncs, rewards, times = [], [], []
    for _ in range(12):
        _, r, term, trunc, info = envs.step(a)
        assert not term.any()
        truncs.append(bool(trunc[0]))
        rewards.append(float(r[0]))
        times.append(float(info["time"][0]))
    # steps 1..5, truncated at 5; step 6 is the autoreset (reward 0, time 0); 7..11, truncated at 11
    assert truncs == [False] * 4 + [True] + [False] * 5 + [True] + [False]
    assert rewards[5] == 0.0 and times[5] == 0.0 and times[4] == pytest.approx(0.5)
    # the noise-free start is the same every episode: the second episode repeats the first
    assert rewards[6:11] == rewards[0:5] and min(rewards[0:5]) > 0.0


def test_same_step_final_obs_and_info() -> None:
    envs = AmigoBotVectorEnv(num_envs=3, max_episode_steps=2, autoreset_mode="SameStep")
    envs.reset(seed=1)
    a = np.full((3, 2), 0.27)
    envs.step(a)
    obs, _, _, trunc, info = envs.step(a)
    assert trunc.all()
    assert info["_final_obs"].all() and info["_final_info"].all()
    assert info["final_info"]["time"] == pytest.approx([0.2] * 3)
    assert info["time"] == pytest.approx([0.0] * 3)  # the obs/info returned are of the new episodes
    assert not np.array_equal(np.stack(list(info["final_obs"])), obs)


def test_infos_have_masks_and_single_env_keys() -> None:
    envs = AmigoBotVectorEnv(num_envs=4)
    _, info = envs.reset(seed=0)
    single = gym.make("AmigoBot-v0")
    _, sinfo = single.reset(seed=0)
    for k, v in sinfo.items():
        assert k in info and info[f"_{k}"].all()
        if isinstance(v, dict):
            assert set(info[k]) == set(v) | {f"_{t}" for t in v}
        else:
            assert np.shape(info[k]) == (4, *np.shape(v))


@pytest.mark.parametrize(
    "actions",
    [np.zeros((3, 2)), np.zeros((4,)), np.full((4, 2), np.nan), np.array([[0, 0], [0, 0], [0, np.inf], [0, 0.0]])],
)
def test_bad_actions(actions: np.ndarray) -> None:
    envs = AmigoBotVectorEnv(num_envs=4)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        envs.step(actions)


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"num_envs": 0}, ValueError, "num_envs"),
        ({"num_envs": 2.5}, ValueError, "num_envs"),
        ({"max_episode_steps": 0}, ValueError, "max_episode_steps"),
        ({"render_mode": "human"}, ValueError, "render_mode"),
        ({"autoreset_mode": "sometimes"}, ValueError, "autoreset_mode"),
        ({"radius": -1.0}, ValueError, "radius"),
        ({"colour": "red"}, TypeError, "colour"),
    ],
)
def test_bad_construction(kwargs: dict[str, Any], exc: type[Exception], match: str) -> None:
    with pytest.raises(exc, match=match):
        AmigoBotVectorEnv(**kwargs)


@pytest.mark.parametrize(
    ("reset_kw", "match"),
    [
        ({"seed": [1, 2]}, "length"),
        ({"options": {"pose": np.zeros((2, 3))}}, "shape"),
        ({"options": {"pose": (0.0, np.nan, 0.0)}}, "finite"),
        ({"options": {"reset_mask": np.zeros(3, dtype=bool)}}, "True"),
        ({"options": {"foo": 1}}, "foo"),
    ],
)
def test_bad_reset(reset_kw: dict[str, Any], match: str) -> None:
    envs = AmigoBotVectorEnv(num_envs=3)
    with pytest.raises(ValueError, match=match):
        envs.reset(**reset_kw)


def test_disabled_mode_refuses_stepping_finished_envs() -> None:
    envs = AmigoBotVectorEnv(num_envs=2, max_episode_steps=1, autoreset_mode=AutoresetMode.DISABLED)
    envs.reset(seed=0)
    envs.step(np.zeros((2, 2)))
    with pytest.raises(RuntimeError, match="reset"):
        envs.step(np.zeros((2, 2)))


def test_bench_env_smoke_and_bad_arguments(tmp_path: Any, capsys: pytest.CaptureFixture[str]) -> None:
    import json

    from amigo_gym.tools.bench.env import main

    out = tmp_path / "bench.json"
    assert main(["--quick", "--sizes", "1", "8", "--sync-max", "8", "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "Pendulum-v1" in printed and "native / CartPole" in printed
    doc = json.loads(out.read_text())
    assert [r["n"] for r in doc["vector"]] == [1, 8] and all(r["sync"] > 0 for r in doc["vector"])
    assert doc["single"]["amigobot_us"] > 0 and doc["single"]["pendulum_us"] > 0
    assert main(["--sizes", "0", "--skip-single"]) == 2
    assert "sizes[0]" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main(["--repeats", "x"])
    assert exc.value.code == 2


def test_step_before_reset_is_refused() -> None:
    envs = AmigoBotVectorEnv(num_envs=2)
    with pytest.raises(gym.error.ResetNeeded):
        envs.step(np.zeros((2, 2)))
