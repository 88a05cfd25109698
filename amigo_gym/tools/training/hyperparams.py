"""rl-zoo hyperparameter files (one mapping per env id) for ``amigo-gym train``: read, check, make SB3 arguments.

rl-zoo's idioms: a string ``policy_kwargs``, ``normalize``, ``noise_type``/``noise_std``, ``lin_<x>`` schedules; every
other key must be a keyword of the algorithm's SB3 class.
"""

from __future__ import annotations

import ast
import contextlib
import inspect
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from amigo_gym.model.params import check_real

ENV_ID = "AmigoBot-v0"

#: the ``policy`` of TD3 with the low-pass actor (:mod:`amigo_gym.tools.training.sb3_lowpass`)
LOWPASS_POLICY = "LowPassMlpPolicy"
#: keys of the file that are not keyword arguments of the algorithm class
META_KEYS = ("n_timesteps", "n_envs", "policy", "normalize", "noise_type", "noise_std", "normalize_kwargs")

#: keyword arguments of the algorithm class that a file may not set (train sets them, or they need objects)
RESERVED = (  # noqa: SIM905
    "policy env seed device verbose tensorboard_log _init_setup_model action_noise replay_buffer_class "
    "rollout_buffer_class"
).split()

#: the torch names a ``policy_kwargs`` string may use (``{name: module}``), bare or behind ``nn.``/``optim.``,
#: ``th.`` or ``torch.`` and that module
TORCH_NAMES: dict[str, str] = {
    **dict.fromkeys(("ReLU", "Tanh", "ELU", "LeakyReLU", "SiLU", "GELU", "Sigmoid", "Softplus", "Identity"), "nn"),
    **dict.fromkeys(("Adam", "AdamW", "RMSprop", "SGD"), "optim"),
}


def _torch_object(name: str) -> Any:
    """The torch class a ``policy_kwargs`` name stands for (``ValueError`` if it is not in :data:`TORCH_NAMES`)."""
    head, _, attr = name.rpartition(".")
    if (module := TORCH_NAMES.get(attr)) is not None and head in ("", module, f"th.{module}", f"torch.{module}"):
        import torch

        return getattr(getattr(torch, module), attr)
    allowed = ", ".join(f"{v}.{k}" for k, v in TORCH_NAMES.items())
    raise ValueError(f"policy_kwargs: unknown name {name!r}; allowed: {allowed}")


def parse_python_literal(text: str, what: str = "policy_kwargs") -> Any:
    """An rl-zoo Python expression, parsed, not evaluated: literals, lists, tuples, dicts, ``dict(k=v)``, a sign, and
    the torch names of :data:`TORCH_NAMES` (the classes). ``ValueError``: any other construct."""
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except SyntaxError as exc:
        raise ValueError(f"{what}: cannot parse {text!r}: {exc.msg}") from None

    def walk(node: ast.expr) -> Any:
        if isinstance(node, ast.Constant | ast.UnaryOp):
            with contextlib.suppress(ValueError):
                value = ast.literal_eval(node)
                if isinstance(value, int | float | str | bool | type(None)):
                    return value
        if isinstance(node, ast.List):
            return [walk(e) for e in node.elts]
        if isinstance(node, ast.Tuple):
            return tuple(walk(e) for e in node.elts)
        if isinstance(node, ast.Dict):
            if any(k is None for k in node.keys):
                raise ValueError(f"{what}: ** is not allowed in {text!r}")
            return {walk(k): walk(v) for k, v in zip(node.keys, node.values, strict=True) if k is not None}
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "dict":
            if node.args or any(k.arg is None for k in node.keywords):
                raise ValueError(f"{what}: write dict(key=value, ...) in {text!r}")
            return {str(k.arg): walk(k.value) for k in node.keywords}
        if isinstance(node, ast.Name | ast.Attribute):
            return _torch_object(ast.unparse(node))
        raise ValueError(f"{what}: {ast.unparse(node)!r} is not allowed (only literals, lists, dicts, torch names)")

    return walk(tree.body)


def _schedule(key: str, value: Any) -> float | Callable[[float], float]:
    """A number, or ``lin_<x>``: linear from ``x`` at the start to 0 at the end."""
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    if isinstance(value, str):
        text = value.strip()
        try:
            return _Linear(float(text[4:])) if text.startswith("lin_") else float(text)
        except ValueError:
            pass
    raise ValueError(f"{key} must be a number or 'lin_<x>', got {value!r}")


@dataclass(frozen=True)
class _Linear:
    """rl-zoo's ``lin_<x>``: ``progress_remaining * x`` (picklable, so SB3 can save the model)."""

    start: float

    def __call__(self, progress_remaining: float) -> float:
        return progress_remaining * self.start


@dataclass
class Hyperparams:
    """A checked hyperparameter file: its meta keys (``None``: absent) and the algorithm class's keyword arguments
    (``policy_kwargs`` parsed, schedules made)."""

    n_timesteps: int | None = None
    n_envs: int | None = None
    policy: str = "MlpPolicy"
    normalize: dict[str, Any] | None = None
    noise_type: str | None = None
    noise_std: float = 0.1
    kwargs: dict[str, Any] = field(default_factory=dict)

    def action_noise(self, n_actions: int) -> Any:
        if self.noise_type is None:
            return None
        from stable_baselines3.common.noise import NormalActionNoise, OrnsteinUhlenbeckActionNoise

        mean, sigma = np.zeros(n_actions), self.noise_std * np.ones(n_actions)
        return (NormalActionNoise if self.noise_type == "normal" else OrnsteinUhlenbeckActionNoise)(mean, sigma)


def sb3_class(algo: str) -> Any:
    """SB3's class of ``algo`` (``ppo``: ``PPO``...)."""
    import stable_baselines3

    return getattr(stable_baselines3, algo.upper())


def _normalize(value: Any, gamma: Any) -> dict[str, Any] | None:
    if isinstance(value, str):
        text = value.strip().lower()
        value = text == "true" if text in ("true", "false") else parse_python_literal(value, "normalize")
    if value is None or value is False:
        return None
    kw: dict[str, Any] = {}
    if isinstance(value, Mapping):
        allowed = {"norm_obs", "norm_reward", "clip_obs", "clip_reward", "gamma", "epsilon"}
        if bad := sorted(str(k) for k in value if k not in allowed):
            raise ValueError(f"normalize: unknown key(s) {', '.join(bad)}; allowed: {', '.join(sorted(allowed))}")
        kw = dict(value)
    elif value is not True:
        raise ValueError(f"normalize must be true, false or a mapping of VecNormalize keywords, got {value!r}")
    if gamma is not None:
        kw.setdefault("gamma", float(gamma))
    return kw


def parse_hyperparams(algo: str, hp: Mapping[str, Any], where: str = "hyperparams") -> Hyperparams:
    """The checked mapping ``hp`` of a file for ``algo``; ``ValueError``: unknown keys (all) or the first bad value."""
    allowed = (set(inspect.signature(sb3_class(algo)).parameters) - {"self", *RESERVED}) | set(META_KEYS)
    if unknown := sorted(str(k) for k in hp if k not in allowed):
        raise ValueError(
            f"{where}: unknown key(s) for {algo}: {', '.join(unknown)} (allowed: {', '.join(sorted(allowed))})"
        )
    out = Hyperparams()
    for name in ("n_timesteps", "n_envs"):
        if (v := hp.get(name)) is not None:
            if isinstance(v, float) and v.is_integer():
                v = int(v)  # rl-zoo files often write 1e6
            if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                raise ValueError(f"{where}: {name} must be an integer >= 1, got {v!r}")
            setattr(out, name, v)
    pk = hp.get("policy_kwargs")
    pk = parse_python_literal(pk) if isinstance(pk, str) else pk
    policy = hp.get("policy", "MlpPolicy")
    if policy == LOWPASS_POLICY:
        if algo != "td3":
            raise ValueError(f"{where}: policy {LOWPASS_POLICY} is for td3, not {algo}")
        alpha = pk.get("filter_alpha") if isinstance(pk, Mapping) else None
        check_real(f"{where}: policy_kwargs", "filter_alpha", alpha, 0.0, 1.0, low_open=True)
        if isinstance(pk, Mapping) and "prev_index" in pk:
            raise ValueError(f"{where}: policy_kwargs.prev_index comes from the env's observation, not the file")
        out.policy = LOWPASS_POLICY
    elif policy != "MlpPolicy":
        raise ValueError(
            f"{where}: policy must be MlpPolicy (the observation is a vector) or {LOWPASS_POLICY} (td3), got {policy!r}"
        )
    out.normalize = _normalize(hp.get("normalize", hp.get("normalize_kwargs")), hp.get("gamma"))
    if (noise := hp.get("noise_type")) is not None:
        if algo == "ppo":
            raise ValueError(f"{where}: noise_type applies to sac and td3, not ppo")
        if noise not in ("normal", "ornstein-uhlenbeck"):
            raise ValueError(f"{where}: noise_type must be 'normal' or 'ornstein-uhlenbeck', got {noise!r}")
        out.noise_type = str(noise)
        std = hp.get("noise_std", 0.1)
        if isinstance(std, bool) or not isinstance(std, int | float) or not std >= 0:
            raise ValueError(f"{where}: noise_std must be a number >= 0, got {std!r}")
        out.noise_std = float(std)
    elif "noise_std" in hp:
        raise ValueError(f"{where}: noise_std without noise_type")
    kw = {k: v for k, v in hp.items() if k not in META_KEYS}
    for key in ("learning_rate", "clip_range", "clip_range_vf"):
        if key in kw and kw[key] is not None:
            kw[key] = _schedule(key, kw[key])
    if pk is not None:
        if not isinstance(pk, Mapping):
            raise ValueError(f"{where}: policy_kwargs must be a mapping, got {pk!r}")
        pk = dict(pk)
        for key in ("activation_fn", "optimizer_class"):
            if isinstance(pk.get(key), str):
                pk[key] = _torch_object(pk[key])
        kw["policy_kwargs"] = pk
    if isinstance(kw.get("train_freq"), list):
        kw["train_freq"] = tuple(kw["train_freq"])
    out.kwargs = kw
    return out


def load_hyperparams(path: str | os.PathLike[str], env_id: str = ENV_ID) -> dict[str, Any]:
    """The ``env_id`` mapping of a YAML file, unchecked; ``ValueError``: not YAML or no such mapping."""
    import yaml

    try:
        with open(path, encoding="utf-8") as f:
            doc = yaml.safe_load(f)
    except yaml.YAMLError as exc:
        raise ValueError(f"{path}: not valid YAML: {' '.join(str(exc).split())}") from None
    if not isinstance(doc, dict) or env_id not in doc or not isinstance(doc[env_id], dict):
        raise ValueError(f"{path}: expected a mapping with the key {env_id!r}")
    return dict(doc[env_id])
