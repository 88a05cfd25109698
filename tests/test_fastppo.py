"""The fast PPO (amigo_gym.tools.training.fastppo) and its numpy policies (amigo_gym.policies.learned); tiny budgets."""

from __future__ import annotations

import copy
import json
import subprocess
import sys
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import pytest

torch = pytest.importorskip("torch")

from amigo_gym.io import sha256_file, vouch  # noqa: E402
from amigo_gym.policies import AnalyticTrackingPolicy, load_pretrained  # noqa: E402
from amigo_gym.policies.learned import (  # noqa: E402
    HISTORY_FIELDS,
    FastPolicy,
    FeatureBuilder,
    FeatureSpec,
    RunningMeanStd,
    env_action,
)
from amigo_gym.task.v1 import obs_fields  # noqa: E402
from amigo_gym.tools.training.fastppo import (  # noqa: E402
    ActorCritic,
    FastPPOSettings,
    _Buffers,
    _new_run,
    gae,
    rollout,
    train,
    update,
)

KW = {"path": "mixed", "speed": [0.1, 0.4], "randomize": "mild"}


def tiny(**kw: object) -> FastPPOSettings:
    base: dict[str, object] = {
        "env_kwargs": KW,
        "total_steps": 512,
        "num_envs": 16,
        "rollout_steps": 8,
        "epochs": 2,
        "minibatch_size": 64,
        "eval_every": 256,
        "eval_envs": 2,
        "max_episode_steps": 20,
        "checkpoint_every": 128,
        "hidden": (8, 8),
    }
    base.update(kw)
    return FastPPOSettings(**base)  # type: ignore[arg-type]


def weights(path: Path) -> dict[str, np.ndarray]:
    ck = torch.load(path / "checkpoint.pt", weights_only=False)
    return {k: v.numpy().copy() for k, v in ck["net"].items()}


# --------------------------------------------------------------------------- settings
@pytest.mark.parametrize(
    ("field", "value", "match"),
    [
        ("num_envs", 0, "num_envs"),
        ("gamma", 1.0, "gamma"),
        ("learning_rate", float("nan"), "learning_rate"),
        ("minibatch_size", 100, "minibatch_size"),
        ("residual_bound", 3.0, "residual_bound"),
        ("filter_alpha", 0.0, "filter_alpha"),
        ("history", 21, "history"),
        ("hidden", (64, 0), "hidden"),
        ("caps_temporal", -1.0, "caps_temporal"),
        ("residual_penalty", -0.1, "residual_penalty"),
        ("residual_penalty", float("nan"), "residual_penalty"),
        ("residual_penalty", 101.0, "residual_penalty"),
        ("nominal_fraction", -0.1, "nominal_fraction"),
        ("nominal_fraction", 1.0, "nominal_fraction"),
    ],
)
def test_settings_refuse_bad_values(field: str, value: object, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        tiny(**{field: value})


def test_settings_refuse_wrong_types_and_bad_env_kwargs() -> None:
    with pytest.raises(TypeError, match="num_envs"):
        tiny(num_envs=2.5)
    with pytest.raises(TypeError, match="norm_reward"):
        tiny(norm_reward="yes")
    with pytest.raises(ValueError):
        tiny(env_kwargs={"path": "mixed", "speed": -1.0})
    with pytest.raises(ValueError, match=r"residual_penalty.*residual_bound"):
        tiny(residual_penalty=0.1)  # a penalty on the correction of a policy that has none
    s = tiny()
    assert FastPPOSettings.from_json(json.loads(json.dumps(s.to_json()))) == s
    with pytest.raises(ValueError, match="unknown"):
        FastPPOSettings.from_json({"nonsense": 1})


# --------------------------------------------------------------------------- normalisation
def test_running_mean_std_matches_numpy_over_batches() -> None:
    rng = np.random.default_rng(0)
    batches = [rng.normal(3.0, 2.0, size=(n, 4)) for n in (5, 17, 1, 40)]
    rms = RunningMeanStd.zeros(4)
    for b in batches:
        rms.update(b)
    allx = np.concatenate(batches)
    # the 1e-4 prior count of mean 0 / var 1 shifts the result by O(1e-4 / n)
    np.testing.assert_allclose(rms.mean, allx.mean(axis=0), rtol=1e-4, atol=1e-4)
    np.testing.assert_allclose(rms.var, allx.var(axis=0), rtol=1e-3)
    back = RunningMeanStd.from_dict(json.loads(json.dumps(rms.to_dict())))
    np.testing.assert_array_equal(back.mean, rms.mean)
    np.testing.assert_array_equal(back.var, rms.var)
    assert back.count == rms.count
    z = rms.normalize(allx)
    assert abs(z.mean()) < 1e-3 and abs(z.std() - 1) < 1e-2


# --------------------------------------------------------------------------- training runs
def test_same_seed_same_weights_other_seed_other_weights(tmp_path: Path) -> None:
    for name, seed in (("a", 3), ("b", 3), ("c", 4)):
        train(tiny(seed=seed), tmp_path / name, log=None)
    wa, wb, wc = (weights(tmp_path / n) for n in "abc")
    for k in wa:
        np.testing.assert_array_equal(wa[k], wb[k])
    assert any(not np.array_equal(wa[k], wc[k]) for k in wa)
    assert sha256_file(tmp_path / "a" / "model.zip") != ""
    ja = json.loads((tmp_path / "a" / "curve.json").read_text())
    jb = json.loads((tmp_path / "b" / "curve.json").read_text())
    assert [r["eval_h_rms_m"] for r in ja] == [r["eval_h_rms_m"] for r in jb]
    assert [r["env_steps"] for r in ja] == [0.0, 256.0, 512.0]


def test_resume_gives_the_uninterrupted_result(tmp_path: Path) -> None:
    s = tiny(
        residual_bound=0.3, history=2, caps_temporal=0.1, caps_spatial=0.1, residual_penalty=0.5, nominal_fraction=0.25
    )
    train(s, tmp_path / "whole", log=None)
    rec = train(s, tmp_path / "cut", log=None, until_steps=256)
    assert rec["timesteps"] == 256 and not rec["finished"] and not (tmp_path / "cut" / "model.zip").exists()
    with pytest.raises(FileExistsError, match="resume"):
        train(s, tmp_path / "cut", log=None)
    with pytest.raises(ValueError, match="settings differ"):
        train(tiny(seed=9, residual_bound=0.3, history=2), tmp_path / "cut", log=None, resume=True)
    rec = train(s, tmp_path / "cut", log=None, resume=True)
    assert rec["timesteps"] == 512 and rec["finished"]
    w1, w2 = weights(tmp_path / "whole"), weights(tmp_path / "cut")
    for k in w1:
        np.testing.assert_array_equal(w1[k], w2[k])
    ck1 = torch.load(tmp_path / "whole" / "checkpoint.pt", weights_only=False)
    ck2 = torch.load(tmp_path / "cut" / "checkpoint.pt", weights_only=False)
    assert ck1["obs_rms"] == ck2["obs_rms"] and ck1["ret_rms"] == ck2["ret_rms"]
    assert sha256_file(tmp_path / "whole" / "model.zip") == sha256_file(tmp_path / "cut" / "model.zip")


def test_a_second_process_on_the_run_folder_is_refused_and_changes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """train-fast locks its run folder (tools.runs.RunLock): a second train-fast or --resume on a folder in use
    stops with one line and leaves the running run's files as they were; once the lock is free the resume runs."""
    import yaml

    from amigo_gym.tools import runs
    from amigo_gym.tools.training.fastppo import main

    s = tiny()
    out = tmp_path / "run"
    train(s, out, log=None, until_steps=256)
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    hp = {k: v for k, v in s.to_json().items() if k not in ("env_kwargs", "seed")}
    (tmp_path / "hp.yml").write_text(yaml.safe_dump({"AmigoBot-v1": hp}))
    argv = [
        "--out",
        str(out),
        "--resume",
        "--quiet",
        "--env-kwargs",
        json.dumps(KW),
        "--hyperparams",
        str(tmp_path / "hp.yml"),
    ]
    with runs.RunLock(out):  # as another process holds it (flock: a second open file description conflicts)
        assert main(argv) != 0
        err = capsys.readouterr().err.strip()
        assert "in use by another amigo-gym process" in err and len(err.splitlines()) == 1, err
        with pytest.raises(runs.RunLockedError):
            train(s, out, log=None, resume=True)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name != runs.LOCK_NAME} == before
    rec = train(s, out, log=None, resume=True)
    assert rec["finished"] and rec["timesteps"] == 512


def test_checkpoint_written_before_a_new_field_resumes_with_its_default(tmp_path: Path) -> None:
    """A checkpoint whose settings lack ``residual_penalty`` (older code) resumes as the default (0)."""
    s = tiny(residual_bound=0.3, history=2)
    train(s, tmp_path / "whole", log=None)
    train(s, tmp_path / "cut", log=None, until_steps=256)
    ck = torch.load(tmp_path / "cut" / "checkpoint.pt", weights_only=False)
    del ck["settings"]["residual_penalty"]
    torch.save(ck, tmp_path / "cut" / "checkpoint.pt")
    vouch(sha256_file(tmp_path / "cut" / "checkpoint.pt"))  # as an older version of this installation wrote it
    train(s, tmp_path / "cut", log=None, resume=True)
    w1, w2 = weights(tmp_path / "whole"), weights(tmp_path / "cut")
    for k in w1:
        np.testing.assert_array_equal(w1[k], w2[k])
    with pytest.raises(ValueError, match="settings differ"):  # a non-default value is still a different run
        train(tiny(residual_bound=0.3, history=2, residual_penalty=0.5), tmp_path / "cut", log=None, resume=True)


def test_nominal_fraction_steps_the_last_robots_as_the_nominal_robot() -> None:
    """The trainer's robots equal two separately stepped vector envs: env_kwargs, then the nominal robot."""
    from amigo_gym.tools.training.fastppo import _training_env

    kw = {"path": "mixed", "speed": [0.1, 0.4], "randomize": {"wheel_radius": [0.9, 1.1], "delay": [0.1, 0.3]}}
    s = tiny(env_kwargs=kw, nominal_fraction=0.25, max_episode_steps=7)
    env = _training_env(s)
    nominal = {"path": "mixed", "speed": [0.1, 0.4]}
    refs = [
        gym.make_vec("AmigoBot-v1", num_envs=n, max_episode_steps=7, autoreset_mode="SameStep", **k)
        for n, k in ((12, kw), (4, nominal))
    ]
    seeds = list(range(50, 66))
    obs, _ = env.reset(seed=seeds)
    ref_obs = np.concatenate([refs[0].reset(seed=seeds[:12])[0], refs[1].reset(seed=seeds[12:])[0]])
    np.testing.assert_array_equal(obs, ref_obs)
    rng = np.random.default_rng(0)
    ended = 0
    for _ in range(10):  # past the time limit: autoresets and final observations
        a = rng.uniform(-1, 1, (16, 2))
        got = env.step(a)
        want = [refs[0].step(a[:12]), refs[1].step(a[12:])]
        for j in range(4):
            np.testing.assert_array_equal(got[j], np.concatenate([w[j] for w in want]))
        for i in range(16):
            part, row = (0, i) if i < 12 else (1, i - 12)
            info = want[part][4]
            if "final_obs" in info and info["_final_obs"][row]:
                np.testing.assert_array_equal(got[4]["final_obs"][i], info["final_obs"][row])
                ended += 1
            else:
                assert got[4]["final_obs"][i] is None
    assert ended >= 16  # every robot hit the 7-step limit at least once
    # the nominal rows differ from what env_kwargs' randomised robots would do with the same seeds
    alt = gym.make_vec("AmigoBot-v1", num_envs=4, max_episode_steps=7, autoreset_mode="SameStep", **kw)
    alt.reset(seed=seeds[12:])
    env.reset(seed=seeds)
    a = np.full((16, 2), 0.5)
    for _ in range(3):
        o_alt = alt.step(a[12:])[0]
        o = env.step(a)[0]
    assert not np.array_equal(o[12:], o_alt)
    env.close()
    for e in (*refs, alt):
        e.close()


def test_residual_penalty_shrinks_the_mean_correction(tmp_path: Path) -> None:
    """Same seed and data stream: the L2 penalty on mu leaves a smaller mean correction than none."""
    mags = []
    for pen in (0.0, 20.0):
        s = tiny(residual_bound=0.3, history=2, residual_penalty=pen, learning_rate=3e-3, total_steps=2048,
                 eval_every=10**6, log_std_init=0.0)  # fmt: skip
        train(s, tmp_path / f"p{pen}", log=None)
        pol = FastPolicy.load(tmp_path / f"p{pen}" / "model.zip")
        z = np.random.default_rng(0).standard_normal((256, pol.builder.dim))
        feats = pol.obs_rms.mean + z * np.sqrt(pol.obs_rms.var)  # normalised features ~ N(0, I)
        mags.append(float(np.sqrt((pol.mean_output(feats) ** 2).sum(-1).mean())))
    assert mags[0] > 0.02  # without the penalty the correction has grown from its ~0 start
    assert mags[1] < 0.5 * mags[0]


def _autograd_update(s: FastPPOSettings, net: ActorCritic, opt: torch.optim.Optimizer, buf: _Buffers) -> None:
    """The PPO update written as a loss for autograd (the reference of ``fastppo.update``'s closed-form gradient)."""
    t_len, log_std = s.rollout_steps, net.log_std
    batch, d = s.num_envs * t_len, buf.x.shape[-1]
    adv, ret = (v.reshape(batch) for v in gae(s, buf))
    bx, bnext = buf.x[:t_len].reshape(batch, d), buf.x[1:].reshape(batch, d)
    bu, blogp, bsame = buf.u.reshape(batch, 2), buf.logp.reshape(batch), 1.0 - buf.done.reshape(batch)
    for _ in range(s.epochs):
        perm = torch.randperm(batch)
        for k in range(0, batch, s.minibatch_size):
            idx = perm[k : k + s.minibatch_size]
            xb, mu, same = bx[idx], net.actor(bx[idx]), bsame[idx]
            z = (bu[idx] - mu) / log_std.exp()
            ratio = ((-0.5 * z * z - log_std - 0.5 * np.log(2.0 * np.pi)).sum(-1) - blogp[idx]).exp()
            a = (adv[idx] - adv[idx].mean()) / (adv[idx].std() + 1e-8)
            pg = torch.max(-a * ratio, -a * ratio.clamp(1.0 - s.clip_coef, 1.0 + s.clip_coef)).mean()
            vloss = 0.5 * (net.value(xb) - ret[idx]).pow(2).mean()
            entropy = (log_std + 0.5 * np.log(2.0 * np.pi * np.e)).sum()
            caps_t = ((net.actor(bnext[idx]) - mu).pow(2).sum(-1) * same).sum() / same.sum().clamp(min=1.0)
            loss = pg + s.vf_coef * vloss - s.ent_coef * entropy + s.caps_temporal * caps_t
            loss = loss + s.residual_penalty * mu.pow(2).sum(-1).mean()
            if s.caps_spatial > 0:  # draws the noise only then
                mu_n = net.actor(xb + s.caps_sigma * torch.randn_like(xb))
                loss = loss + s.caps_spatial * (mu_n - mu).pow(2).sum(-1).mean()
            opt.zero_grad()
            loss.backward()  # type: ignore[no-untyped-call]
            torch.nn.utils.clip_grad_norm_(net.parameters(), s.max_grad_norm)
            opt.step()


@pytest.mark.parametrize(
    "kw",
    [
        {"epochs": 1, "minibatch_size": 128, "max_grad_norm": 100.0},  # one step: the raw gradients compared
        {"caps_temporal": 0.0, "caps_spatial": 0.0, "residual_penalty": 0.0, "ent_coef": 0.0},
    ],
)
def test_update_matches_autograd_of_the_ppo_loss(kw: dict[str, object]) -> None:
    """``update``'s closed-form gradient of the loss (clipped surrogate, value, entropy, CAPS temporal and spatial,
    residual penalty) is autograd's: from the same state and random draws, the same gradients and weights."""
    s = tiny(**{"caps_temporal": 0.3, "caps_spatial": 0.2, "caps_sigma": 0.5, "residual_bound": 0.5,
                "residual_penalty": 0.4, "ent_coef": 0.01, "clip_coef": 0.1, "learning_rate": 3e-3, **kw})  # fmt: skip
    builder = FeatureBuilder(s.spec())
    r = _new_run(s, builder, "cpu")
    buf = _Buffers.allocate(s.rollout_steps, s.num_envs, builder.dim, "cpu")
    for _ in range(3):  # past the 20-step time limit: episode ends in the last rollout
        rollout(s, r, builder, buf, "cpu")
        update(s, r, buf)
    assert float(buf.done.sum()) > 0
    net, opt = copy.deepcopy((r.net, r.opt))
    rng = torch.get_rng_state()
    update(s, r, buf)
    torch.set_rng_state(rng)
    _autograd_update(s, net, opt, buf)
    for (name, p), q in zip(r.net.named_parameters(), net.parameters(), strict=True):
        assert torch.allclose(p.grad, q.grad, rtol=1e-4, atol=1e-7), name
        assert torch.allclose(p, q, rtol=1e-5, atol=1e-6), name


def test_numpy_policy_matches_the_torch_actor_and_round_trips(tmp_path: Path) -> None:
    s = tiny(history=1)
    train(s, tmp_path / "r", log=None)
    pol = FastPolicy.load(tmp_path / "r" / "model.zip")
    ck = torch.load(tmp_path / "r" / "checkpoint.pt", weights_only=False)
    # the checkpoint's normaliser is the one saved in the model
    np.testing.assert_array_equal(pol.obs_rms.mean, np.asarray(ck["obs_rms"]["mean"]))

    net = ActorCritic(pol.builder.dim, s.hidden, s.log_std_init)
    net.load_state_dict(ck["net"])
    x = np.random.default_rng(1).normal(size=(7, pol.builder.dim))
    with torch.no_grad():
        ref = net.actor(torch.as_tensor(pol.obs_rms.normalize(x), dtype=torch.float32)).double().numpy()
    np.testing.assert_allclose(pol.mean_output(x), ref, rtol=1e-5, atol=1e-6)
    pol.save(tmp_path / "copy.zip")
    again = FastPolicy.load(tmp_path / "copy.zip")
    env = gym.make_vec("AmigoBot-v1", num_envs=3, **KW)
    obs, _ = env.reset(seed=[0, 1, 2])
    a1, st1 = pol.predict(obs, episode_start=np.ones(3, bool))
    a2, st2 = again.predict(obs, state=None, episode_start=np.ones(3, bool))
    np.testing.assert_array_equal(a1, a2)
    np.testing.assert_array_equal(st1, st2)
    assert a1.shape == (3, 2) and a1.dtype == np.float32 and np.all(np.abs(a1) <= 1)
    single, _ = pol.predict(obs[0], state=st1[:1], episode_start=False)
    assert single.shape == (2,)
    env.close()


# --------------------------------------------------------------------------- features, residual
def test_history_holds_the_previous_observations() -> None:
    spec = FeatureSpec(KW, history=3)
    b = FeatureBuilder(spec)
    names = obs_fields(spec.params())
    idx = [names.index(f) for f in HISTORY_FIELDS]
    rng = np.random.default_rng(0)
    obs_seq = [rng.normal(size=(2, b.obs_dim)) for _ in range(5)]
    state = b.initial_state(2)
    feats = []
    for k, o in enumerate(obs_seq):
        f, _, state = b(o, state, np.full(2, k == 0))
        feats.append(f)
    d = b.obs_dim
    # at step 4 the history is steps 1, 2, 3 (oldest first); at step 1 it is step 0 three times (filled at start)
    expect4 = np.concatenate([obs_seq[j][:, idx] for j in (1, 2, 3)], axis=1)
    np.testing.assert_array_equal(feats[4][:, d:], expect4)
    expect1 = np.concatenate([obs_seq[0][:, idx]] * 3, axis=1)
    np.testing.assert_array_equal(feats[1][:, d:], expect1)
    # an episode start in row 1 refills that row's history with its own observation
    f, _, _ = b(obs_seq[0], state, np.array([False, True]))
    np.testing.assert_array_equal(f[1, d:], np.tile(obs_seq[0][1, idx], 3))


def test_env_action_residual_stays_within_bound_and_filter_limits_change() -> None:
    rng = np.random.default_rng(0)
    base = rng.uniform(-1, 1, size=(1000, 2))
    u = rng.normal(scale=5.0, size=(1000, 2))
    prev = rng.uniform(-1, 1, size=(1000, 2))
    a = env_action(u, base, prev, 0.3, 1.0)
    assert np.all(np.abs(a - base) <= 0.3 + 1e-12) and np.all(np.abs(a) <= 1)
    assert np.max(np.abs(a - base)) > 0.29  # the bound is reached, not just respected
    f = env_action(u, base, prev, 0.0, 0.25)
    np.testing.assert_allclose(f, prev + 0.25 * (np.clip(u, -1, 1) - prev))


@pytest.mark.parametrize("gain", [1.0, 1.8])
def test_residual_policy_in_an_env_stays_within_its_bound_of_the_analytic_action(gain: float) -> None:
    """A residual network with huge random weights (saturated output) in real episodes: every action within
    0.2 of the analytic controller's of gain ``residual_gain``, computed independently with its own integral state."""
    kw = {"path": "circle", "randomize": {"delay": [0.0, 0.2]}}
    spec = FeatureSpec(kw, history=2, residual_bound=0.2, residual_gain=gain)
    dim = FeatureBuilder(spec).dim
    rng = np.random.default_rng(5)
    layers = [
        (rng.normal(scale=30, size=(dim, 8)), rng.normal(size=8)),
        (rng.normal(scale=30, size=(8, 2)), np.zeros(2)),
    ]
    pol = FastPolicy(spec, layers, np.zeros(2), RunningMeanStd.zeros(dim))
    ref = AnalyticTrackingPolicy(spec.params(), gain=gain)
    env = gym.make_vec("AmigoBot-v1", num_envs=4, path="circle", randomize={"delay": [0.0, 0.2]})
    obs, _ = env.reset(seed=[0, 1, 2, 3])
    starts = np.ones(4, bool)
    worst = 0.0
    for _ in range(60):
        a, _ = pol.predict(obs, episode_start=starts)
        a0, _ = ref.predict(obs, episode_start=starts)
        worst = max(worst, float(np.max(np.abs(a - a0))))
        obs, _, te, tr, _ = env.step(a)
        starts = te | tr
    env.close()
    assert 0.15 < worst <= 0.2 + 1e-6
    with pytest.raises(ValueError, match=r"FeatureSpec.residual_gain must be a finite number in \(0, 10\], got 12.0"):
        FeatureSpec(kw, residual_bound=0.2, residual_gain=12.0)


# --------------------------------------------------------------------------- load_pretrained
def test_load_pretrained_checks_sha256(tmp_path: Path) -> None:
    spec = FeatureSpec(KW)
    dim = FeatureBuilder(spec).dim
    rng = np.random.default_rng(0)
    pol = FastPolicy(spec, [(rng.normal(size=(dim, 4)), np.zeros(4)), (rng.normal(size=(4, 2)), np.zeros(2))],
                     np.zeros(2), RunningMeanStd.zeros(dim))  # fmt: skip
    z = tmp_path / "m.zip"
    pol.save(z)
    with pytest.raises(FileNotFoundError, match="manifest"):
        load_pretrained(z)
    (tmp_path / "m.json").write_text(json.dumps({"sha256": "0" * 64}))
    with pytest.raises(ValueError, match="sha256"):
        load_pretrained(z)
    (tmp_path / "m.json").write_text(json.dumps({"algo": "fastppo"}))
    with pytest.raises(ValueError, match="no sha256"):
        load_pretrained(z)
    (tmp_path / "m.json").write_text(json.dumps({"sha256": sha256_file(z)}))
    got = load_pretrained(z)
    obs = np.zeros((3, dim), np.float32)
    obs[:, 2] = 1.0
    a, _ = got.predict(obs, state=None, episode_start=None, deterministic=True)
    b, _ = pol.predict(obs, state=None, episode_start=None, deterministic=True)
    np.testing.assert_array_equal(a, b)


def test_load_pretrained_opens_the_shipped_sb3_zips() -> None:
    pytest.importorskip("stable_baselines3")
    from amigo_gym.data import pretrained_dir

    z = pretrained_dir() / "v1" / "td3lp" / "td3lp_s0.zip"  # an SB3 TD3 zip (low-pass actor)
    if not z.is_file():
        pytest.fail(f"shipped model {z} missing")
    model = load_pretrained(z)
    from stable_baselines3 import TD3

    assert isinstance(model, TD3)  # the SB3 model itself, loaded by the manifest's algo
    env = gym.make_vec("AmigoBot-v1", num_envs=2)
    obs, _ = env.reset(seed=[0, 1])
    a, _ = model.predict(obs, state=None, episode_start=None, deterministic=True)
    assert np.asarray(a).shape == (2, 2)
    env.close()


def test_learned_policies_import_no_torch() -> None:
    code = "import sys, amigo_gym.policies.learned; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "False"


def test_cli_bad_value_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from amigo_gym.tools.cli import main  # in this process: the check is the message, not the process (torch's import)

    capsys.readouterr()
    try:
        rc = main(["train-fast", "--out", str(tmp_path / "x"), "--gamma", "2"])
    except SystemExit as exc:  # an argparse refusal
        rc = exc.code if isinstance(exc.code, int) else 1
    err = capsys.readouterr().err
    assert rc == 2 and len(err.strip().splitlines()) == 1 and "gamma" in err, err
    assert not (tmp_path / "x").exists()


def test_benchmark_runs_fast_models_as_numpy_policies(tmp_path: Path) -> None:
    """``amigo-gym benchmark`` takes a fast-PPO zip (not mistaken for SB3's PPO by the 'ppo' in its name) and
    runs it through the same predict as a direct rollout; a v0 scenario is unavailable (other observation)."""
    from amigo_gym.tools.training import benchmark as bm

    spec = FeatureSpec({"path": "circle"}, history=1, residual_bound=0.2)
    dim = FeatureBuilder(spec).dim
    rng = np.random.default_rng(0)
    pol = FastPolicy(spec, [(rng.normal(size=(dim, 4)), np.zeros(4)), (rng.normal(size=(4, 2)), np.zeros(2))],
                     np.zeros(2), RunningMeanStd.zeros(dim))  # fmt: skip
    z = tmp_path / "ppo_fast_s3.zip"
    pol.save(z)
    (agent,) = bm.parse_agents([f"fast={z}"])
    assert agent.algo == "fastppo" and agent.seed == 3
    sc = bm.Scenario("c", "AmigoBot-v1", {"path": "circle"}, seeds=(0, 1), max_steps=30, held_out=False,
                     description="test")  # fmt: skip
    env = gym.make("AmigoBot-v1", path="circle")
    got = bm.evaluate(agent.instantiate(env), env, sc)
    # the same two episodes rolled out directly
    venv = gym.make_vec("AmigoBot-v1", num_envs=2, path="circle", max_episode_steps=30)
    obs, _ = venv.reset(seed=[0, 1])
    fresh = FastPolicy.load(z)
    state, starts, err = None, np.ones(2, bool), []
    for _ in range(30):
        a, state = fresh.predict(obs, state=state, episode_start=starts)
        starts = np.zeros(2, bool)
        obs, _, _, _, info = venv.step(a)
        err.append(info["cross_track_error"])
    rms = np.sqrt(np.mean(np.square(np.array(err)), axis=0))
    np.testing.assert_allclose([g["h_rms_m"] for g in got], rms, rtol=1e-12)
    v0 = gym.make("AmigoBot-v0")
    with pytest.raises(bm.Unavailable, match="observation"):
        agent.instantiate(v0)
    env.close(), venv.close(), v0.close()


def _rate_matches(count: float, t: float, rate: float) -> bool:
    """``rate`` (rounded to 0.1) is ``count / t`` for some true time within the 0.01 s rounding of ``t``.

    On a short run (0.2 s) the rounding of the time alone moves the rate by a few per cent, so a relative
    tolerance is wrong; this is the propagated bound.
    """
    return t > 0.005 and abs(count / t - rate) <= 0.051 + count * 0.0051 / (t * (t - 0.005))


def test_bench_train_writes_rates_and_ratios(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")
    from amigo_gym.tools.bench.train import cpu_model, main

    out = tmp_path / "b.json"
    assert main(["--fast-steps", "16384", "--sb3-steps", "256", "--skip-sb3-fastconfig", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert doc["cpu_model"] == cpu_model() != ""
    fast, sb3 = doc["runs"]["fastppo"], doc["runs"]["sb3_shipped"]
    assert fast["env_steps"] == 16384 and sb3["env_steps"] == 16 * 256  # SB3 rounds up to whole rollouts
    assert _rate_matches(fast["env_steps"], fast["wall_s"], fast["sps"])
    assert 0 < fast["loop_wall_s"] <= fast["wall_s"] and fast["sps_loop"] >= fast["sps"]  # iterations: part of the call
    assert fast["cpu_s_rollout"] > 0 and fast["cpu_s_update"] > 0
    # the device named (auto: cpu without CUDA, the CPU's name), the env's share of the iterations
    want = "cuda" if torch.cuda.is_available() else "cpu"
    assert fast["device"] == want and sb3["device"] == "cpu" and sb3["device_name"] == cpu_model()
    assert want == "cuda" or fast["device_name"] == cpu_model()
    assert 0 < fast["env_share"] < 1 and fast["torch_threads"] == 1
    assert doc["ratios"]["fastppo/sb3_shipped"] == pytest.approx(fast["sps"] / sb3["sps"], abs=0.01)
    assert main(["--fast-steps", "10", "--json", str(out)]) == 2  # below one rollout: one-line error
    with pytest.raises(SystemExit) as exc:  # argparse's one line: the choices
        main(["--device", "gpu"])
    assert exc.value.code == 2


def test_bench_train_offpolicy_entries_write_rates(tmp_path: Path) -> None:
    """Every off-policy entry runs (sb3-contrib is in the train extra: no skip) and writes its rates and config."""
    import sb3_contrib
    import stable_baselines3
    import yaml

    from amigo_gym.data import hyperparams_dir
    from amigo_gym.tools.bench.train import algo_class, main

    assert algo_class("crossq") is sb3_contrib.CrossQ and algo_class("tqc") is sb3_contrib.TQC
    assert algo_class("sac") is stable_baselines3.SAC and algo_class("td3") is stable_baselines3.TD3
    out = tmp_path / "b.json"
    argv = ["--fast-steps", "16384", "--sb3-steps", "256", "--skip-sb3-fastconfig", "--json", str(out)]
    argv += ["--offpolicy", "sac,td3,crossq,tqc", "--offpolicy-steps", "8", "--offpolicy-ht-steps", "128"]
    assert main(argv) == 0
    doc = json.loads(out.read_text())
    sac_yml = yaml.safe_load((hyperparams_dir() / "sac.yml").read_text())["AmigoBot-v1"]
    for algo in ("sac", "td3", "crossq", "tqc"):
        for config, n_envs, loop in (("shipped", 1, 8), ("ht", 128, 128)):
            r = doc["runs"][f"{algo}_{config}"]
            cfg = r["config"]
            assert cfg["n_envs"] == n_envs and cfg["net_arch"] == [64, 64]
            # the warm-up ends exactly at learning_starts (no update: SB3 trains once num_timesteps > learning_starts)
            assert r["env_steps"] == cfg["learning_starts"] + loop and r["loop_env_steps"] == loop
            # every gradient step in the loop, as many as the configuration's ratio asks
            assert r["grad_steps"] == r["loop_grad_steps"] == round(loop * cfg["gradient_steps_per_env_step"]) == 8
            # the rates are counts over the times; rates rounded to 0.1, times to 0.01 s: the propagated bound
            for count, rate, t in ((loop, "sps_loop", "loop_wall_s"), (8, "gsps_loop_cpu", "loop_cpu_s")):
                assert _rate_matches(count, r[t], r[rate]), (algo, config, rate)
            assert 0 < r["loop_wall_s"] <= r["wall_s"]
            assert _rate_matches(r["env_steps"], r["wall_s"], r["sps"]), (algo, config, "sps")
            assert doc["ratios"][f"fastppo/{algo}_{config}"] == pytest.approx(
                doc["runs"]["fastppo"]["sps"] / r["sps"], abs=0.01
            )
        shipped = doc["runs"][f"{algo}_shipped"]["config"]
        assert shipped["batch_size"] == sac_yml["batch_size"] and shipped["gradient_steps"] == sac_yml["gradient_steps"]
        assert doc["runs"][f"{algo}_ht"]["config"]["batch_size"] == 2048
    assert "tau" not in doc["runs"]["crossq_shipped"]["config"]  # CrossQ has no target network
    assert doc["runs"]["td3_shipped"]["config"]["noise_type"] == "normal"
    assert main(["--offpolicy", "sac,ddpg", "--json", str(out)]) == 2  # unknown algorithm: one-line error


def test_offpolicy_models_have_64x64_networks() -> None:
    """Actor and every critic of each off-policy model: two hidden layers of 64 units (the bench's "same network")."""
    from amigo_gym.tools.bench.train import _venv, make_model, offpolicy_config

    venv = _venv(1, 0)
    try:
        for algo in ("sac", "td3", "crossq", "tqc"):
            model = make_model(algo, offpolicy_config(algo, "shipped"), venv)
            linears = [m for m in model.policy.modules() if isinstance(m, torch.nn.Linear)]
            n_obs, n_act = venv.observation_space.shape[0], venv.action_space.shape[0]
            # inputs: the observation (actor) or observation + action (critics); outputs: the action (mean, log std),
            # one Q value or TQC's 25 quantiles; everything between: 64
            ins, outs = {m.in_features for m in linears}, {m.out_features for m in linears}
            assert ins <= {n_obs, n_obs + n_act, 64} and outs <= {64, n_act, 1, 25} and 64 in ins & outs, (
                algo,
                ins,
                outs,
            )
            assert sum(m.out_features == 64 for m in linears) >= 2 * 3, algo  # actor and >= 2 critics, 2 layers each
    finally:
        venv.close()


# --------------------------------------------------------------------------- device, threads, determinism, manifest
def test_device_auto_resolves_to_cuda_only_where_torch_sees_one(monkeypatch: pytest.MonkeyPatch) -> None:
    from amigo_gym.tools.training.fastppo import resolve_device

    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    assert resolve_device("auto") == "cuda" and resolve_device("cuda") == "cuda" and resolve_device("cpu") == "cpu"
    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    assert resolve_device("auto") == "cpu" and resolve_device("cpu") == "cpu"
    with pytest.raises(ValueError, match=r"device = 'cuda'.*allowed: auto, cpu"):
        resolve_device("cuda")
    with pytest.raises(ValueError, match=r"device must be one of auto, cpu, cuda, got 'gpu'"):
        tiny(device="gpu")
    assert tiny().device == "auto"


def test_cuda_without_one_and_too_many_env_threads_are_one_line_errors(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from amigo_gym.tools.training import fastppo

    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    base = ["--total-steps", "128", "--num-envs", "16", "--rollout-steps", "8", "--minibatch-size", "64"]
    for extra, match in (
        (["--device", "cuda"], "device = 'cuda'"),
        (["--env-threads", str(fastppo._numba_threads_limit() + 1)], "env_threads must be in [1, "),
    ):
        capsys.readouterr()
        assert fastppo.main(["--out", str(tmp_path / "x"), "--quiet", *base, *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and match in err, err
        assert not (tmp_path / "x").exists()  # refused before anything is written


def test_same_command_twice_same_weights_and_the_manifest_names_the_machine(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """The determinism users can check: one train-fast command line run twice (same machine, same seed) gives the
    same weights bit for bit; run.json records the git revision (the one at the start: a checkout that moves during
    training does not rename the code that ran), CPU, thread counts and device; a --total-steps below one rollout is
    rounded up in one said line, and no 'nan' return is printed before an episode ends."""
    from amigo_gym.tools.machine import cpu_model
    from amigo_gym.tools.training import fastppo
    from amigo_gym.tools.training.fastppo import main

    updated, real_update, real_revision = [], fastppo.update, fastppo.git_revision
    monkeypatch.setattr(fastppo, "update", lambda *a: (updated.append(1), real_update(*a))[1])
    monkeypatch.setattr(fastppo, "git_revision", lambda: "b" * 40 if updated else real_revision())

    argv = ["--env-kwargs", json.dumps(KW), "--total-steps", "100", "--num-envs", "16", "--rollout-steps", "8",
            "--epochs", "2", "--minibatch-size", "64", "--hidden", "8", "8", "--max-episode-steps", "20",
            "--eval-envs", "2", "--eval-every", "1000", "--seed", "5", "--device", "cpu"]  # fmt: skip
    outs = []
    for name in ("a", "b"):
        capsys.readouterr()
        assert main(["--out", str(tmp_path / name), *argv]) == 0
        outs.append(capsys.readouterr().out)
    assert "total_steps 100 rounded up to 128: whole rollouts of num_envs x rollout_steps = 128" in outs[0]
    progress = [line for line in outs[0].splitlines() if "128 / 128 steps" in line]
    assert len(progress) == 1 and "no episode finished yet" in progress[0] and "nan" not in progress[0], outs[0]
    wa, wb = weights(tmp_path / "a"), weights(tmp_path / "b")
    assert wa.keys() == wb.keys()
    for k in wa:
        np.testing.assert_array_equal(wa[k], wb[k])
    assert (tmp_path / "a" / "model.zip").read_bytes() == (tmp_path / "b" / "model.zip").read_bytes()
    rec = json.loads((tmp_path / "a" / "run.json").read_text())
    assert rec["timesteps"] == 128 and rec["device"] == "cpu" and rec["cpu"] == cpu_model()
    assert rec["torch_threads"] == 1 and rec["numba_threads"] >= 1 and rec["settings"]["device"] == "cpu"
    rev = rec["git_revision"]
    assert rev != "b" * 40 and (rev == "unknown" or len(rev.removesuffix("-dirty")) == 40), rev
    assert set(rec["wall_s_this_call"]) == {"env", "rollout", "update", "loop"}
    assert 0 < rec["wall_s_this_call"]["env"] < rec["wall_s_this_call"]["rollout"] <= rec["wall_s_this_call"]["loop"]


def test_manifest_says_unknown_outside_a_git_checkout(monkeypatch: pytest.MonkeyPatch) -> None:
    from amigo_gym.tools.training import fastppo

    monkeypatch.setattr(fastppo, "git_revision", lambda: "not a git checkout")
    assert fastppo.machine_record("cpu")["git_revision"] == "unknown"
    monkeypatch.setattr(fastppo, "git_revision", lambda: "a" * 40 + "-dirty")
    assert fastppo.machine_record("cpu")["git_revision"] == "a" * 40 + "-dirty"


def test_env_threads_run_the_parallel_kernel_with_the_same_weights(tmp_path: Path) -> None:
    """env_threads 2 steps the robots on numba's threads (numba-parallel): the same weights as one thread."""
    for name, n in (("one", 1), ("two", 2)):
        rec = train(tiny(env_threads=n, device="cpu", total_steps=256), tmp_path / name, log=None, evaluate_runs=False)
        assert rec["numba_threads"] == n and rec["torch_threads"] == 1  # numba's start did not change torch's
    w1, w2 = weights(tmp_path / "one"), weights(tmp_path / "two")
    for k in w1:
        np.testing.assert_array_equal(w1[k], w2[k])


def test_gpu_train_bench_runs_on_the_cpu_and_writes_its_json(tmp_path: Path) -> None:
    """experiments/gpu_train_bench.py (the GPU node's prepared measurement) runs here with tiny settings: the
    machine, the throughput and its shares, the trained steps and the ideal-cell figures land in $OUT."""
    root = Path(__file__).resolve().parent.parent
    argv = ["--budget-s", "1", "--n-envs", "32", "--measure-iters", "2", "--env-steps", "2", "--episodes", "1"]
    argv += ["--overlap"]
    env = {**__import__("os").environ, "OUT": str(tmp_path), "PYTHONPATH": str(root)}
    r = subprocess.run([sys.executable, str(root / "experiments" / "gpu_train_bench.py"), *argv], env=env,
                       capture_output=True, text=True, timeout=600)  # fmt: skip
    assert r.returncode == 0, r.stdout[-2000:] + r.stderr[-2000:]
    doc = json.loads((tmp_path / "gpu_train_bench.json").read_text())
    assert (
        doc["device"] == ("cuda" if torch.cuda.is_available() else "cpu") and doc["cpu"] and doc["numba_threads"] >= 1
    )
    t = doc["throughput"]
    assert t["train_sps"] > 0 and t["env_share"] + t["learner_share"] == pytest.approx(1.0, abs=1e-3)
    assert doc["env_only_sps"] > 0 and doc["training"]["total_steps"] % (32 * 16) == 0
    q = doc["ideal_cells"]
    assert len(q["cells"]) == 11 and q["episodes_per_cell"] == 1 and q["analytic"]["h_rms_iqm_mm"] > 0
    assert q["ratio"] == pytest.approx(q["fastppo"]["h_rms_iqm_mm"] / q["analytic"]["h_rms_iqm_mm"])
    assert t["env_steps"] == 32 * 16 and [x["n_envs"] for x in doc["throughput_sizes"]] == [32]
    [o] = doc["throughput_overlap"]  # --overlap: the same N again with train-fast --overlap
    assert o["overlap"] and not t["overlap"] and o["n_envs"] == 32
    assert o["ratio_to_plain"] == pytest.approx(o["train_sps"] / t["train_sps"], rel=1e-2)
    assert json.loads((tmp_path / "gpu_run.json").read_text())["sha256"] == doc["training"]["sha256"]
    assert (tmp_path / "gpu_model.zip").stat().st_size > 0
    c = doc["curve"]  # the validation curve: from the untrained policy to the trained one, against training time
    assert c[0]["env_steps"] == 0 and c[-1]["env_steps"] == doc["training"]["total_steps"]
    assert np.all(np.diff([row["train_s"] for row in c]) >= 0) and c[-1]["ratio_to_analytic"] > 0


def test_overlap_is_deterministic_and_resumes(tmp_path: Path) -> None:
    """overlap: the halves' env steps on a second thread; twice the same weights, and a run cut and resumed too."""
    s = tiny(overlap=True, nominal_fraction=0.25, history=2, device="cpu")
    for name in ("a", "b"):
        train(s, tmp_path / name, log=None)
    train(s, tmp_path / "c", log=None, until_steps=256)
    train(s, tmp_path / "c", log=None, resume=True)
    wa, wb, wc = (weights(tmp_path / n) for n in "abc")
    for k in wa:
        np.testing.assert_array_equal(wa[k], wb[k])
        np.testing.assert_array_equal(wa[k], wc[k])


@pytest.mark.parametrize("env_threads", [1, 2])
def test_overlap_threaded_equals_the_same_schedule_inline(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, env_threads: int
) -> None:
    """The threaded schedule gives the weights of the same two halves stepped inline (no thread), bit for bit; the
    env steps run on the second thread with env_threads of numba's, never two at once; each robot starts as
    without overlap (its env seed kept)."""
    import threading

    from amigo_gym.tools.training import fastppo

    lock, seen, real = threading.Lock(), list[tuple[bool, bool, int]](), fastppo._timed_step

    def step(env: object, a: np.ndarray) -> tuple[tuple[object, ...], float]:
        alone = lock.acquire(blocking=False)  # False: another env step is under way
        seen.append((alone, threading.current_thread() is threading.main_thread(), fastppo.numba.get_num_threads()))
        try:
            time.sleep(0.002)  # widens the window of a second step
            return real(env, a)
        finally:
            if alone:
                lock.release()

    monkeypatch.setattr(fastppo, "_timed_step", step)
    s = tiny(overlap=True, env_threads=env_threads, device="cpu", residual_bound=0.3, caps_temporal=0.1)
    train(s, tmp_path / "thread", log=None, evaluate_runs=False)
    assert seen == [(True, False, env_threads)] * 64  # 4 iterations x 8 steps x 2 halves
    monkeypatch.setattr(fastppo, "_OVERLAP_THREAD", False)
    train(s, tmp_path / "inline", log=None, evaluate_runs=False)
    assert seen[64:] == [(True, True, env_threads)] * 64
    w1, w2 = weights(tmp_path / "thread"), weights(tmp_path / "inline")
    for k in w1:
        np.testing.assert_array_equal(w1[k], w2[k])
    b = FeatureBuilder(s.spec())
    np.testing.assert_array_equal(_new_run(s, b, "cpu").obs, _new_run(tiny(), b, "cpu").obs)


def test_overlap_option_is_recorded(tmp_path: Path) -> None:
    from amigo_gym.tools.training.fastppo import main

    argv = ["--env-kwargs", json.dumps(KW), "--total-steps", "128", "--num-envs", "16", "--rollout-steps", "8",
            "--epochs", "1", "--minibatch-size", "64", "--hidden", "8", "--max-episode-steps", "20",
            "--eval-envs", "1", "--device", "cpu", "--quiet", "--overlap"]  # fmt: skip
    assert main(["--out", str(tmp_path / "on"), *argv]) == 0
    assert main(["--out", str(tmp_path / "off"), *argv[:-1]]) == 0
    for name, on in (("on", True), ("off", False)):
        assert json.loads((tmp_path / name / "settings.json").read_text())["overlap"] is on
        assert json.loads((tmp_path / name / "run.json").read_text())["settings"]["overlap"] is on
    with pytest.raises(ValueError, match="even num_envs"):
        tiny(overlap=True, num_envs=15, minibatch_size=15)
