"""TD3 with the low-pass actor (``policy: LowPassMlpPolicy``, :mod:`amigo_gym.tools.training.sb3_lowpass`).

References: the filter recomputed in numpy from the saved weights (not through the module), and the env's own
``previous_command`` field over a rollout.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from stable_baselines3 import TD3

import amigo_gym  # noqa: F401
from amigo_gym.task.v1 import obs_fields
from amigo_gym.tools.training.hyperparams import parse_hyperparams
from amigo_gym.tools.training.sb3_lowpass import LowPassTD3Policy, check_filter, policy_for
from amigo_gym.tools.training.train import make_train_env

ALPHA = 0.3


def _model(alpha: float = ALPHA, seed: int = 0) -> Any:
    venv = make_train_env(4, "native", seed, None, "AmigoBot-v1", {"path": "circle"})
    cls, pk = policy_for(venv, {"net_arch": [16, 16], "filter_alpha": alpha})
    return TD3(cls, venv, policy_kwargs=pk, learning_starts=64, batch_size=32, seed=seed, device="cpu")


def _numpy_target(model: Any, obs: np.ndarray) -> np.ndarray:
    """``tanh(mlp(o))`` from the actor's weights, in numpy (ReLU hidden layers, SB3's default)."""
    x = obs.astype(np.float64)
    layers = [m for m in model.policy.actor.mu if hasattr(m, "weight")]
    for i, layer in enumerate(layers):
        x = x @ layer.weight.detach().numpy().astype(np.float64).T + layer.bias.detach().numpy()
        x = np.maximum(x, 0.0) if i < len(layers) - 1 else np.tanh(x)
    return x


def test_actor_is_the_filter_of_the_network(tmp_path: Path) -> None:
    model = _model()
    model.learn(200)  # some updates: weights away from their initialisation
    env = gym.make("AmigoBot-v1", path="circle")
    names = obs_fields(env.unwrapped.params)  # type: ignore[attr-defined]
    i1, i2 = names.index("previous_command_1"), names.index("previous_command_2")
    obs, _ = env.reset(seed=3)
    rng = np.random.default_rng(0)
    batch = np.repeat(obs[None, :], 8, axis=0)
    batch[:, [i1, i2]] = rng.uniform(-1, 1, (8, 2))  # a range of previous commands
    a, _ = model.predict(batch, deterministic=True)
    prev = batch[:, [i1, i2]].astype(np.float64)
    want = prev + ALPHA * (_numpy_target(model, batch) - prev)
    np.testing.assert_allclose(a, want, atol=1e-5)
    # the zip is the filtered policy: loaded without knowing of the filter, the same actions
    model.save(tmp_path / "m.zip")
    loaded = TD3.load(tmp_path / "m.zip", device="cpu")
    assert isinstance(loaded.policy, LowPassTD3Policy)
    assert loaded.policy.filter_alpha == ALPHA and loaded.policy.prev_index == (i1, i2)
    np.testing.assert_allclose(loaded.predict(batch, deterministic=True)[0], a, atol=1e-7)


def test_command_change_is_bounded_in_a_rollout() -> None:
    """Over an episode, the env's command changes by at most ``2 alpha`` per step (|u - p| <= 2)."""
    model = _model(alpha=0.1, seed=1)
    env = gym.make("AmigoBot-v1", path="circle")
    names = obs_fields(env.unwrapped.params)  # type: ignore[attr-defined]
    idx = [names.index("previous_command_1"), names.index("previous_command_2")]
    obs, _ = env.reset(seed=5)
    prev = obs[idx].astype(np.float64)
    steps = 0
    for _ in range(60):
        a, _ = model.predict(obs, deterministic=True)
        obs, _, term, trunc, _ = env.step(a)
        new = obs[idx].astype(np.float64)
        np.testing.assert_allclose(new, a, atol=1e-6)  # the observation echoes the command it was given
        assert np.all(np.abs(new - prev) <= 2 * 0.1 + 1e-6)
        prev, steps = new, steps + 1
        if term or trunc:
            break
    assert steps > 10


@pytest.mark.parametrize(
    ("alpha", "index", "match"),
    [
        (0.0, (0, 1), "filter_alpha must be a finite number in"),
        (1.5, (0, 1), "filter_alpha must be a finite number in"),
        (math.nan, (0, 1), "filter_alpha must be a finite number in"),
        ("0.3", (0, 1), "filter_alpha must be a real number in"),
        (True, (0, 1), "filter_alpha must be a real number in"),
        (0.3, (1, 1), "prev_index must be two distinct"),
        (0.3, (0, 99), "prev_index must be two distinct"),
        (0.3, (0,), "prev_index must be two distinct"),
    ],
)
def test_check_filter_refuses(alpha: Any, index: Any, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        check_filter(alpha, index, 20)


@pytest.mark.parametrize(
    ("algo", "hp", "match"),
    [
        ("sac", {"policy": "LowPassMlpPolicy", "policy_kwargs": {"filter_alpha": 0.3}}, "is for td3, not sac"),
        ("td3", {"policy": "LowPassMlpPolicy"}, "filter_alpha must be a real number in"),
        (
            "td3",
            {"policy": "LowPassMlpPolicy", "policy_kwargs": {"filter_alpha": 2}},
            "filter_alpha must be a finite number in",
        ),
        (
            "td3",
            {"policy": "LowPassMlpPolicy", "policy_kwargs": {"filter_alpha": 0.3, "prev_index": [0, 1]}},
            "prev_index comes from the env",
        ),
        ("td3", {"policy": "CnnPolicy"}, "policy must be MlpPolicy"),
    ],
)
def test_yaml_refusals(algo: str, hp: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match) as e:
        parse_hyperparams(algo, hp)
    assert "\n" not in str(e.value)


def test_yaml_accepts_and_v0_is_refused() -> None:
    parsed = parse_hyperparams("td3", {"policy": "LowPassMlpPolicy", "policy_kwargs": "dict(filter_alpha=0.5)"})
    assert parsed.policy == "LowPassMlpPolicy" and parsed.kwargs["policy_kwargs"] == {"filter_alpha": 0.5}
    venv = make_train_env(2, "native", 0, None, "AmigoBot-v0", None)
    with pytest.raises(ValueError, match="needs AmigoBot-v1"):
        policy_for(venv, {"filter_alpha": 0.5})
