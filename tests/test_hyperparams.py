"""rl-zoo idioms in ``--hyperparams``: safe parsing of ``policy_kwargs`` strings, schedules, noise, normalize."""

from __future__ import annotations

import pickle
from typing import Any

import numpy as np
import pytest
import torch

from amigo_gym.tools.training.hyperparams import _Linear, parse_hyperparams, parse_python_literal


def test_policy_kwargs_string_is_parsed_not_evaluated() -> None:
    got = parse_python_literal("dict(net_arch=[64, 64], activation_fn=nn.ReLU, log_std_init=-2.5, ortho_init=False)")
    assert got == {"net_arch": [64, 64], "activation_fn": torch.nn.ReLU, "log_std_init": -2.5, "ortho_init": False}
    assert parse_python_literal("dict(net_arch=dict(pi=[32], vf=[32, 32]), activation_fn=th.nn.Tanh)") == {
        "net_arch": {"pi": [32], "vf": [32, 32]},
        "activation_fn": torch.nn.Tanh,
    }
    assert parse_python_literal("{'optimizer_class': th.optim.AdamW, 'x': (1, 2)}") == {
        "optimizer_class": torch.optim.AdamW,
        "x": (1, 2),
    }


@pytest.mark.parametrize(
    "text",
    [
        "__import__('os').system('echo pwned')",
        "dict(a=open('/etc/passwd'))",
        "nn.Module",
        "os.system",
        "optim.ReLU",
        "[1] * 3",
        "dict(**x)",
        "lambda: 0",
        "dict(net_arch=[64,",
    ],
)
def test_policy_kwargs_refuses_code(text: str) -> None:
    with pytest.raises(ValueError, match="policy_kwargs"):
        parse_python_literal(text)


def test_rl_zoo_idioms() -> None:
    hp = parse_hyperparams(
        "ppo",
        {
            "n_timesteps": 1e6,
            "policy": "MlpPolicy",
            "normalize": True,
            "learning_rate": "lin_3e-4",
            "clip_range": "lin_0.2",
            "gamma": 0.98,
            "policy_kwargs": "dict(net_arch=[64, 64], activation_fn=nn.Tanh)",
        },
    )
    assert hp.n_timesteps == 1_000_000
    assert hp.normalize == {"gamma": 0.98}
    lr, clip = hp.kwargs["learning_rate"], hp.kwargs["clip_range"]
    assert (lr(1.0), lr(0.5), lr(0.0)) == (3e-4, 1.5e-4, 0.0)
    assert (clip(1.0), clip(0.25)) == (0.2, 0.05)
    assert pickle.loads(pickle.dumps(lr)) == _Linear(3e-4)  # SB3 saves schedules with the model
    assert hp.kwargs["policy_kwargs"] == {"net_arch": [64, 64], "activation_fn": torch.nn.Tanh}
    assert parse_hyperparams("ppo", {"normalize": "{'norm_obs': True, 'norm_reward': False}"}).normalize == {
        "norm_obs": True,
        "norm_reward": False,
    }
    assert parse_hyperparams("ppo", {"normalize": False}).normalize is None


def test_noise_types() -> None:
    from stable_baselines3.common.noise import NormalActionNoise, OrnsteinUhlenbeckActionNoise

    ou = parse_hyperparams("td3", {"noise_type": "ornstein-uhlenbeck", "noise_std": 0.3}).action_noise(2)
    assert isinstance(ou, OrnsteinUhlenbeckActionNoise)
    np.testing.assert_array_equal(ou._sigma, [0.3, 0.3])
    normal = parse_hyperparams("sac", {"noise_type": "normal", "noise_std": 0.05}).action_noise(2)
    assert isinstance(normal, NormalActionNoise)
    np.testing.assert_array_equal(normal._sigma, [0.05, 0.05])


@pytest.mark.parametrize(
    ("algo", "hp", "match"),
    [
        ("ppo", {"n_step": 64, "frame_stack": 4, "gamma": 0.9}, r"unknown key\(s\) for ppo: frame_stack, n_step \("),
        ("sac", {"clip_range": 0.2}, r"unknown key\(s\) for sac: clip_range"),
        ("ppo", {"noise_type": "normal"}, "not ppo"),
        ("td3", {"noise_type": "pink"}, "noise_type"),
        ("ppo", {"learning_rate": "cos_0.1"}, "lin_"),
        ("ppo", {"normalize": {"norm_obs": True, "bogus": 1}}, "bogus"),
        ("ppo", {"policy": "CnnPolicy"}, "MlpPolicy"),
        ("ppo", {"seed": 3}, "seed"),
    ],
)
def test_refusals_are_one_line(algo: str, hp: dict[str, Any], match: str) -> None:
    with pytest.raises(ValueError, match=match) as exc:
        parse_hyperparams(algo, hp)
    assert "\n" not in str(exc.value)
