"""The curvature curriculum (issue 18, item 7): random-path parameters of ``path="mixed"``, the vector env's
``set_path_params``, :func:`amigo_gym.task.v1.feasible_random_curvature` and fast PPO's ``curriculum_*`` settings.
Tiny budgets; references built independently (``amigo_gym.paths.random_path`` from its seed, closed forms, a fresh
env constructed with the final parameters)."""

from __future__ import annotations

import math
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

from amigo_gym.io import sha256_file, vouch
from amigo_gym.model.params import RobotParams
from amigo_gym.paths import random_path
from amigo_gym.task import v1 as tracking
from amigo_gym.task.v1 import feasible_random_curvature


def _max_abs_kappa(path: object) -> float:
    """max |kappa| of a ClothoidPath from its segments (linear curvature: the ends of each segment)."""
    return max(max(abs(g.curvature), abs(g.curvature + g.curvature_rate * g.length)) for g in path.segments)  # type: ignore[attr-defined]


# --------------------------------------------------------------------------- path_params of "mixed"
def test_mixed_path_params_apply_to_its_random_paths_only() -> None:
    env = gym.make_vec("AmigoBot-v1", num_envs=24, path="mixed", path_params={"max_curvature": 3.0})
    env.reset(seed=list(range(24)))
    infos = env.unwrapped.path_infos  # type: ignore[attr-defined]
    rnd = [i for i, d in enumerate(infos) if d["family"] == "random"]
    assert rnd, "no random path among 24 mixed episodes"
    for i in rnd:
        ref = random_path(np.random.default_rng(infos[i]["id"]), max_curvature=3.0)
        got = env.unwrapped.paths[i]  # type: ignore[attr-defined]
        assert got.segments == ref.segments
        assert _max_abs_kappa(got) <= 3.0 and _max_abs_kappa(got) > 1.0
    # circles keep their radius range [0.5, 3] m whatever the random paths take
    for d in infos:
        if d["family"] == "circle":
            assert 0.5 <= d["radius"] <= 3.0
    env.close()


def test_mixed_refuses_other_families_parameters() -> None:
    with pytest.raises(ValueError, match=r"path_params\['size'\] is unused with path='mixed'"):
        gym.make_vec("AmigoBot-v1", num_envs=2, path="mixed", path_params={"size": 4.0})
    with pytest.raises(ValueError, match="max_curvature"):
        gym.make_vec("AmigoBot-v1", num_envs=2, path="mixed", path_params={"max_curvature": -1.0})


def test_mixed_checks_the_feasibility_of_its_random_paths() -> None:
    k = feasible_random_curvature(0.4)
    with pytest.raises(ValueError, match="random paths"):
        gym.make_vec(
            "AmigoBot-v1", num_envs=2, path="mixed", speed=0.4,
            path_params={"max_curvature": 1.01 * k, "max_curvature_rate": 1.01 * k},
        )  # fmt: skip


# --------------------------------------------------------------------------- the feasible limit
@pytest.mark.parametrize("speed", [0.1, 0.2, 0.4])
def test_feasible_random_curvature_is_the_envs_limit(speed: float) -> None:
    k = feasible_random_curvature(speed)
    ok = tracking.make_tracking_params("t", path="random", speed=speed,
                                       path_params={"max_curvature": k, "max_curvature_rate": k})  # fmt: skip
    assert tracking.drawn_feasibility_problem(ok) is None
    k2 = 1.0001 * k
    bad = tracking.make_tracking_params("t", path="random", speed=speed,
                                        path_params={"max_curvature": k2, "max_curvature_rate": k2})  # fmt: skip
    assert tracking.drawn_feasibility_problem(bad) is not None


def test_feasible_random_curvature_closed_form_when_the_wheels_bind() -> None:
    # a tiny rate: only the wheel limit binds: (v / r)(1 + l1 sigma / (l3 c)) = w_max, c = sqrt(1 - sigma^2)
    robot = RobotParams()
    v = 0.3
    a = (robot.max_wheel_rate * robot.r1 / v - 1.0) * robot.l3 / robot.l1  # sigma / c
    sigma = a / math.sqrt(1.0 + a * a)
    k = feasible_random_curvature(v, rate_per_curvature=1e-6)
    assert k == pytest.approx(sigma / robot.l3, rel=1e-9)
    # and a smaller rotational ramp lowers the limit
    assert feasible_random_curvature(v, rot_acceleration=0.2) < feasible_random_curvature(v)


@pytest.mark.parametrize(
    ("kw", "match"),
    [({"speed": 0.0}, "speed"), ({"speed": math.nan}, "speed"), ({"speed": 0.2, "rate_per_curvature": -1.0}, "rate")],
)
def test_feasible_random_curvature_refuses_bad_input(kw: dict[str, float], match: str) -> None:
    with pytest.raises(ValueError, match=match):
        feasible_random_curvature(**kw)


# --------------------------------------------------------------------------- the setter
@pytest.mark.parametrize("kernel", ["numpy", "auto"])
def test_set_path_params_equals_an_env_built_with_them(kernel: str) -> None:
    pp = {"max_curvature": 3.0, "max_curvature_rate": 3.0}
    kw = {"path": "random", "speed": [0.1, 0.3], "randomize": "mild", "kernel": kernel}
    a = gym.make_vec("AmigoBot-v1", num_envs=5, max_episode_steps=30, **kw)
    a.unwrapped.set_path_params(pp)  # type: ignore[attr-defined]
    b = gym.make_vec("AmigoBot-v1", num_envs=5, max_episode_steps=30, path_params=pp, **kw)
    oa, _ = a.reset(seed=[3, 4, 5, 6, 7])
    ob, _ = b.reset(seed=[3, 4, 5, 6, 7])
    np.testing.assert_array_equal(oa, ob)
    act = np.random.default_rng(0).uniform(-0.5, 0.5, size=(70, 5, 2))
    for u in act:  # across the 30-step time limit: the restarted robots draw from the new pool too
        ra, rb = a.step(u), b.step(u)
        for x, y in zip(ra[:4], rb[:4], strict=True):
            np.testing.assert_array_equal(x, y)
    assert all(p.segments == q.segments for p, q in zip(a.unwrapped.paths.paths, b.unwrapped.paths.paths, strict=True))  # type: ignore[attr-defined]


def test_set_path_params_refuses_bad_input_and_changes_nothing() -> None:
    env = gym.make_vec("AmigoBot-v1", num_envs=2, path="random", speed=0.4)
    before = env.unwrapped.params  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match="max_curvature"):
        env.unwrapped.set_path_params({"max_curvature": math.nan})  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match=r"wheel rate|rotational"):
        env.unwrapped.set_path_params({"max_curvature": 6.0, "max_curvature_rate": 6.0})  # type: ignore[attr-defined]
    with pytest.raises(ValueError, match="'size'"):
        env.unwrapped.set_path_params({"size": 4.0})  # type: ignore[attr-defined]
    assert env.unwrapped.params is before  # type: ignore[attr-defined]
    fixed = gym.make_vec("AmigoBot-v1", num_envs=2, path="circle")
    with pytest.raises(ValueError, match="only drawn paths"):
        fixed.unwrapped.set_path_params({"max_curvature": 2.0})  # type: ignore[attr-defined]


# --------------------------------------------------------------------------- fast PPO's curriculum
torch = pytest.importorskip("torch")

from amigo_gym.tools.training.fastppo import FastPPOSettings, curriculum_path_params, train  # noqa: E402

RKW = {"path": "random", "speed": [0.1, 0.4], "randomize": "mild"}


def tiny(**kw: object) -> FastPPOSettings:
    base: dict[str, object] = {
        "env_kwargs": RKW, "total_steps": 512, "num_envs": 16, "rollout_steps": 8, "epochs": 2,
        "minibatch_size": 64, "eval_every": 256, "eval_envs": 2, "max_episode_steps": 12,
        "checkpoint_every": 128, "hidden": (8, 8), "curriculum_max_curvature": 4.0, "curriculum_stages": 4,
        "curriculum_fraction": 0.5,
    }  # fmt: skip
    base.update(kw)
    return FastPPOSettings(**base)  # type: ignore[arg-type]


def test_curriculum_schedule_closed_form() -> None:
    s = tiny()  # 4 stages over 256 of 512 steps, 1 -> 4 1/m, the rate with it (the family's ratio 1 1/m)
    want = {0: 1.0, 63: 1.0, 64: 1.75, 127: 1.75, 128: 2.5, 192: 3.25, 255: 3.25, 256: 4.0, 512: 4.0}
    for g, k in want.items():
        got = curriculum_path_params(s, g)
        assert got == {"max_curvature": pytest.approx(k, abs=1e-15), "max_curvature_rate": pytest.approx(k, abs=1e-15)}
    s2 = tiny(
        curriculum_max_curvature_rate=2.5, env_kwargs={**RKW, "path_params": {"max_curvature": 2.0, "length": 8.0}}
    )
    assert curriculum_path_params(s2, 0) == {"max_curvature": 2.0, "max_curvature_rate": 1.0, "length": 8.0}
    assert curriculum_path_params(s2, 10**6) == {"max_curvature": 4.0, "max_curvature_rate": 2.5, "length": 8.0}
    assert curriculum_path_params(tiny(curriculum_max_curvature=0.0), 300) is None


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"curriculum_max_curvature": math.nan}, "curriculum_max_curvature"),
        ({"curriculum_max_curvature": -1.0}, "curriculum_max_curvature"),
        ({"curriculum_max_curvature": 0.5}, "must exceed the start"),
        ({"curriculum_max_curvature": 6.0}, r"curriculum_max_curvature 6 1/m: .*(wheel rate|rotational)"),
        ({"curriculum_fraction": 0.0}, "curriculum_fraction"),
        ({"curriculum_stages": 0}, "curriculum_stages"),
        ({"curriculum_stages": 2.5}, "curriculum_stages"),
        ({"curriculum_max_curvature_rate": math.inf}, "curriculum_max_curvature_rate"),
        ({"env_kwargs": {"path": "circle"}}, "needs env_kwargs path 'random' or 'mixed'"),
    ],
)
def test_curriculum_settings_are_checked(kw: dict[str, object], match: str) -> None:
    with pytest.raises((ValueError, TypeError), match=match):
        tiny(**kw)


def test_curriculum_trains_resumes_bit_for_bit_and_reaches_the_final_paths(tmp_path: Path) -> None:
    s = tiny()
    rec = train(s, tmp_path / "whole", log=None)
    ck = torch.load(tmp_path / "whole" / "checkpoint.pt", weights_only=False)
    import pickle

    env = pickle.loads(ck["env"])
    assert dict(env.params.path_params) == {"max_curvature": 4.0, "max_curvature_rate": 4.0}
    # the robots restarted after the last raise drive the final pool: max |kappa| above the start's 1 1/m
    assert max(_max_abs_kappa(p) for p in env.paths.paths) > 1.0
    assert [c["curriculum_max_curvature"] for c in rec_curve(tmp_path / "whole")] == [1.0, 2.5, 4.0]
    train(s, tmp_path / "cut", log=None, until_steps=128)  # cut in the middle of the raises
    train(s, tmp_path / "cut", log=None, resume=True)
    ck2 = torch.load(tmp_path / "cut" / "checkpoint.pt", weights_only=False)
    for k, v in ck["net"].items():
        np.testing.assert_array_equal(v.numpy(), ck2["net"][k].numpy())
    assert ck["obs_rms"] == ck2["obs_rms"] and ck["ret_rms"] == ck2["ret_rms"]
    np.testing.assert_array_equal(ck["obs"], ck2["obs"])
    assert rec["finished"]


def rec_curve(run: Path) -> list[dict[str, float]]:
    import json

    out: list[dict[str, float]] = json.loads((run / "curve.json").read_text())
    return out


def test_a_checkpoint_without_the_curriculum_fields_resumes(tmp_path: Path) -> None:
    """A checkpoint written before the curriculum fields existed (settings without them) resumes as their defaults."""
    s = tiny(curriculum_max_curvature=0.0, curriculum_stages=8)  # the fields' defaults
    train(s, tmp_path / "r", log=None, until_steps=128)
    ck_path = tmp_path / "r" / "checkpoint.pt"
    ck = torch.load(ck_path, weights_only=False)
    for k in ("curriculum_max_curvature", "curriculum_max_curvature_rate", "curriculum_fraction", "curriculum_stages"):
        del ck["settings"][k]
    torch.save(ck, ck_path)
    vouch(sha256_file(ck_path))  # as an older version of this installation wrote it
    rec = train(s, tmp_path / "r", log=None, resume=True)
    assert rec["finished"]
    with pytest.raises(ValueError, match="settings differ"):
        train(tiny(), tmp_path / "r", log=None, resume=True)  # with a curriculum: other settings


def test_curriculum_raises_the_nominal_robots_paths_too(tmp_path: Path) -> None:
    """With ``nominal_fraction`` the trainer steps two vector envs; each stage reaches both."""
    import pickle

    s = tiny(nominal_fraction=0.25)
    rec = train(s, tmp_path / "run", log=None)
    assert rec["finished"]
    env = pickle.loads(torch.load(tmp_path / "run" / "checkpoint.pt", weights_only=False)["env"])
    assert [e.num_envs for e in env.envs] == [12, 4]
    for e in env.envs:
        assert dict(e.params.path_params) == {"max_curvature": 4.0, "max_curvature_rate": 4.0}
