"""Learned ``AmigoBot-v1`` policies in numpy (fast-PPO models, the residual policy) and :func:`load_pretrained`.

A fast-PPO model: a zip of ``model.json`` (format, settings, observation layout) and ``weights.npz`` (the actor,
the observation normalisation). Features of observations ``o`` ``(N, d)``: ``o``, with ``history = H > 0`` the
:data:`HISTORY_FIELDS` of the ``H`` previous steps (oldest first; at an episode's start the first observation), with
``residual_bound = b > 0`` the base policy's action ``a0`` (``base="analytic"``: the
:class:`~amigo_gym.policies.AnalyticTrackingPolicy`'s; ``"compensator"``: the
:class:`~amigo_gym.policies.DelayCompensatedPolicy`'s, then its estimated delay [s] and quiet flag); normalised,
``clip((x - mean) / sqrt(var + 1e-8), -10, 10)``. The action ``a = clip(u, -1, 1)`` of the output ``u`` (or ``clip(a0
+ b clip(u, -1, 1), -1, 1)``, with ``gate`` the correction zeroed where the quiet flag is off), with ``filter_alpha =
alpha < 1`` ``p + alpha (a - p)`` of the previous command ``p``."""

from __future__ import annotations

import io as _io
import json
import zipfile
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from amigo_gym.io import atomic_save, require_trust, sha256_file
from amigo_gym.model.params import check_real
from amigo_gym.policies.base import Fields, Policy
from amigo_gym.policies.compensator import DelayCompensatedPolicy
from amigo_gym.policies.tracking import DEFAULT_TRACKING_GAIN, AnalyticTrackingPolicy
from amigo_gym.task.v1 import TrackingParams, make_tracking_params

Array = NDArray[np.float64]
#: the ``format`` entry of a fast-PPO model's ``model.json``
FORMAT = "amigo_gym.fastppo/1"
#: fields of the observation kept for ``history`` previous steps (commands and measurements)
HISTORY_FIELDS: tuple[str, ...] = ("cross_track_error", "sin_heading_error", "speed_error", "wheel_rate_1",
                                   "wheel_rate_2", "previous_command_1", "previous_command_2")  # fmt: skip


@dataclass
class RunningMeanStd:
    """Running mean and variance of ``(B, D)`` batches (Chan et al.'s parallel update, as SB3's ``VecNormalize``)."""

    mean: Array
    var: Array
    count: float = 1e-4

    @classmethod
    def zeros(cls, dim: int) -> RunningMeanStd:
        """Mean 0, variance 1, count 1e-4 (SB3's start)."""
        return cls(np.zeros(dim), np.ones(dim))

    def update(self, x: ArrayLike) -> None:
        """Merge a batch ``(B, D)`` (or ``(B,)`` for ``D = 1``)."""
        a = np.asarray(x, dtype=np.float64).reshape(-1, self.mean.size)
        n_b = a.shape[0]
        if n_b == 0:
            return
        m_b = np.einsum("ij->j", a) / n_b  # einsum: no per-row loop of the axis-0 reduction
        dev = a - m_b
        v_b = np.einsum("ij,ij->j", dev, dev) / n_b
        d = m_b - self.mean
        n = self.count + n_b
        self.mean = self.mean + d * (n_b / n)
        self.var = (self.var * self.count + v_b * n_b + d * d * (self.count * n_b / n)) / n
        self.count = n

    def normalize(self, x: Array, out: NDArray[Any] | None = None) -> Array:
        """``clip((x - mean) / sqrt(var + 1e-8), -10, 10)``, into ``out`` (e.g. float32) when given."""
        res: Array = np.divide(np.subtract(x, self.mean), np.sqrt(self.var + 1e-8), out=out)
        return np.clip(res, -10.0, 10.0, out=res)

    def to_dict(self) -> dict[str, Any]:
        return {"mean": self.mean.tolist(), "var": self.var.tolist(), "count": float(self.count)}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> RunningMeanStd:
        return cls(np.asarray(d["mean"], dtype=np.float64), np.asarray(d["var"], dtype=np.float64), float(d["count"]))


@dataclass(frozen=True)
class FeatureSpec:
    """What the network observes and how its output becomes an action (module docstring): the training task's
    ``gym.make`` keywords ``env_kwargs``, ``history`` in [0, 20], ``residual_bound`` in [0, 2] (0: no residual),
    ``filter_alpha`` in (0, 1] (1: no filter), ``residual_gain``, the base's gain ``k`` [1/s] in (0, 1/dt] (the
    compensator's while quiet), ``base`` ``"analytic"`` or ``"compensator"`` and ``gate`` (compensator only)."""

    env_kwargs: Mapping[str, Any]
    history: int = 0
    residual_bound: float = 0.0
    filter_alpha: float = 1.0
    residual_gain: float = DEFAULT_TRACKING_GAIN
    base: str = "analytic"
    gate: bool = False

    def __post_init__(self) -> None:
        o = "FeatureSpec"
        check_real(o, "history", self.history, 0, 20)
        if isinstance(self.history, bool) or not isinstance(self.history, (int, np.integer)):
            raise TypeError(f"{o}.history must be an integer in [0, 20], got {self.history!r}")
        check_real(o, "residual_bound", self.residual_bound, 0.0, 2.0)
        check_real(o, "filter_alpha", self.filter_alpha, 0.0, 1.0, low_open=True)
        if not isinstance(self.env_kwargs, Mapping):
            raise TypeError(f"{o}.env_kwargs must be a mapping, got {type(self.env_kwargs).__name__}")
        check_real(o, "residual_gain", self.residual_gain, 0.0, 1.0 / self.params().dt, low_open=True)
        if self.base not in ("analytic", "compensator"):
            raise ValueError(f"{o}.base must be 'analytic' or 'compensator', got {self.base!r}")
        if self.gate not in (False, True) or (self.gate and (self.base != "compensator" or self.residual_bound <= 0)):
            raise ValueError(f"{o}.gate must be a bool, True only for a residual on the compensator, got {self.gate!r}")

    def params(self) -> TrackingParams:
        """The task settings of ``env_kwargs`` (observation layout, nominal robot, ``dt``)."""
        return make_tracking_params("FeatureSpec", None, **self.env_kwargs)


class FeatureBuilder:
    """The features of raw observations and the base action; the state per row is ``[base state, hist.ravel()]``
    (the analytic controller's integral [m s] or the compensator's state, the history ``(H, 7)``)."""

    def __init__(self, spec: FeatureSpec) -> None:
        self.spec = spec
        p = spec.params()
        self.fields = Fields("FastPolicy", p, v1_only=True)
        names = self.fields.names
        self.obs_dim = len(names)
        self._hist_idx = np.array([names.index(f) for f in HISTORY_FIELDS])
        self._prev_idx = np.array([names.index("previous_command_1"), names.index("previous_command_2")])
        comp = spec.residual_bound > 0 and spec.base == "compensator"
        self.analytic = AnalyticTrackingPolicy(p, spec.residual_gain) if spec.residual_bound > 0 and not comp else None
        self.compensator = DelayCompensatedPolicy(p, spec.residual_gain) if comp else None
        h = spec.history
        self.dim = self.obs_dim + h * len(HISTORY_FIELDS) + (0 if spec.residual_bound <= 0 else 4 if comp else 2)
        self.base_dim = self.compensator.state_dim if self.compensator is not None else 1
        self.state_dim = self.base_dim + h * len(HISTORY_FIELDS)

    def initial_state(self, n: int) -> Array:
        """``(N, state_dim)`` zeros."""
        return np.zeros((n, self.state_dim))

    def __call__(self, obs: Array, state: Array, starts: NDArray[np.bool_]) -> tuple[Array, Array, Array]:
        """``(raw features (N, dim), base action (N, 2) or zeros, new state)``, the features ``obs`` itself without
        history or residual; rows with ``starts`` begin an episode."""
        n, k = obs.shape[0], self.base_dim
        h, f = self.spec.history, len(HISTORY_FIELDS)
        parts = [obs]
        new_state = np.empty_like(state)
        if h:
            cur = obs[:, self._hist_idx]
            hist = np.where(starts[:, None, None], cur[:, None, :], state[:, k:].reshape(n, h, f))
            parts.append(hist.reshape(n, h * f))
            new_state[:, k:] = np.concatenate([hist[:, 1:], cur[:, None, :]], axis=1).reshape(n, h * f)
        base: NDArray[np.float64] = np.zeros((n, 2))
        new_state[:, :k] = np.where(starts[:, None], 0.0, state[:, :k])
        if self.analytic is not None:
            a0, z_out = self.analytic.predict(obs, state=new_state[:, :1], episode_start=None)
            base = np.asarray(a0, dtype=np.float64).reshape(n, 2)
            new_state[:, 0] = z_out.reshape(n)
            parts.append(base)
        elif self.compensator is not None:
            c0, delay, quiet, new_state[:, :k] = self.compensator.compensate(obs, state[:, :k], starts)
            base = c0.astype(np.float32).astype(np.float64)  # as ``predict`` gives it, like the analytic base
            parts += [base, delay[:, None], quiet[:, None]]
        return np.concatenate(parts, axis=1) if len(parts) > 1 else obs, base, new_state

    def correcting(self, features: Array) -> NDArray[np.bool_] | None:
        """With ``gate``: the rows whose correction counts (the compensator's quiet flag, the features' last raw
        column); else None (every row)."""
        return features[:, -1] > 0.5 if self.spec.gate else None

    def previous_command(self, obs: Array) -> Array:
        """``(N, 2)`` previous command of the observation (normalised units)."""
        return obs[:, self._prev_idx].astype(np.float64, copy=False)


def env_action(
    u: Array, base: Array, prev: Array, residual_bound: float, filter_alpha: float, mask: Any = None
) -> Array:
    """The environment's action from the network's output ``u`` ``(N, 2)`` (module docstring); ``mask`` ``(N,)``:
    the rows whose correction counts (None: all)."""
    c = np.clip(u, -1.0, 1.0) if mask is None else np.where(mask[:, None], np.clip(u, -1.0, 1.0), 0.0)
    target = np.clip(base + residual_bound * c, -1.0, 1.0) if residual_bound > 0 else c
    return prev + filter_alpha * (target - prev) if filter_alpha < 1.0 else target


def _mlp(layers: list[tuple[Array, Array]], x: Array) -> Array:
    """``tanh`` hidden layers, linear output: ``x W_i + b_i``."""
    for i, (w, b) in enumerate(layers):
        x = x @ w + b
        if i < len(layers) - 1:
            x = np.tanh(x)
    return x


class FastPolicy(Policy):
    """A fast-PPO model in numpy with SB3's ``predict``; its state ``(N, state_dim)`` per row. ``episode_start=None``
    starts the episodes at a new or all-zero state; ``deterministic=False`` adds noise ``exp(log_std)`` to the mean."""

    def __init__(
        self,
        spec: FeatureSpec,
        layers: list[tuple[Array, Array]],
        log_std: Array,
        obs_rms: RunningMeanStd,
        info: Mapping[str, Any] | None = None,
    ) -> None:
        self.spec, self.builder = spec, FeatureBuilder(spec)
        self._fields = self.builder.fields
        if layers[0][0].shape[0] != self.builder.dim or layers[-1][0].shape[1] != 2:
            raise ValueError(
                f"FastPolicy: the network maps {layers[0][0].shape[0]} -> {layers[-1][0].shape[1]}, the features "
                f"need {self.builder.dim} -> 2"
            )
        self.layers, self.log_std, self.obs_rms = layers, np.asarray(log_std, dtype=np.float64), obs_rms
        self.info: dict[str, Any] = dict(info or {})
        self._rng = np.random.default_rng()

    @property
    def name(self) -> str:
        s = self.spec
        return "fastppo" if s.residual_bound <= 0 else f"fastppo_{'compensator_' * (s.base == 'compensator')}residual"

    def mean_output(self, features: Array) -> Array:
        """The network's mean output ``u`` for raw features ``(N, dim)``."""
        return _mlp(self.layers, self.obs_rms.normalize(features))

    def _act(self, obs: Array, state: Any, episode_start: Any, deterministic: bool) -> tuple[Array, Array]:
        b = self.builder
        s, starts = self._rows(obs.shape[0], state, episode_start, b.state_dim)
        feats, base, s_new = b(obs, s, starts)
        u = self.mean_output(feats)
        if not deterministic:
            u = u + np.exp(self.log_std) * self._rng.standard_normal(u.shape)
        prev, sp = b.previous_command(obs), self.spec
        a = env_action(u, base, prev, sp.residual_bound, sp.filter_alpha, b.correcting(feats))
        return a, self._keep(state, s_new)

    def save(self, path: str | Path) -> None:
        """Write the model zip atomically (``model.json`` + ``weights.npz``)."""
        spec = {**asdict(self.spec), "env_kwargs": dict(self.spec.env_kwargs)}
        meta: dict[str, Any] = {"format": FORMAT, "spec": spec, "obs_fields": list(self.builder.fields.names)}
        meta |= {"n_layers": len(self.layers), "info": self.info}
        arrays: dict[str, Array] = {"log_std": self.log_std, "obs_mean": self.obs_rms.mean, "obs_var": self.obs_rms.var}
        arrays["obs_count"] = np.array([self.obs_rms.count])
        for i, (w, bias) in enumerate(self.layers):
            arrays[f"w{i}"], arrays[f"b{i}"] = w, bias
        buf = _io.BytesIO()
        np.savez(buf, **arrays)  # type: ignore[arg-type]

        def write(tmp: str) -> None:
            with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as z:  # fixed dates: same model, same bytes
                for name, raw in (("model.json", json.dumps(meta, indent=2).encode()), ("weights.npz", buf.getvalue())):
                    z.writestr(zipfile.ZipInfo(name, date_time=(1980, 1, 1, 0, 0, 0)), raw, zipfile.ZIP_DEFLATED)

        atomic_save(write, path, parents=True)

    @classmethod
    def load(cls, path: str | Path) -> FastPolicy:
        """Read a model zip written by :meth:`save` (``ValueError`` if it is not one)."""
        with zipfile.ZipFile(path) as z:
            names = set(z.namelist())
            if "model.json" not in names or "weights.npz" not in names:
                raise ValueError(f"{path}: not a fast-PPO model (no model.json / weights.npz)")
            meta = json.loads(z.read("model.json"))
            w = np.load(_io.BytesIO(z.read("weights.npz")))
        if meta.get("format") != FORMAT:
            raise ValueError(f"{path}: format {meta.get('format')!r}, expected {FORMAT!r}")
        spec = FeatureSpec(**meta["spec"])
        layers = [(w[f"w{i}"], w[f"b{i}"]) for i in range(int(meta["n_layers"]))]
        rms = RunningMeanStd(w["obs_mean"], w["obs_var"], float(w["obs_count"][0]))
        return cls(spec, layers, w["log_std"], rms, meta.get("info"))

    def __repr__(self) -> str:
        kw = ", ".join(f"{k}={v!r}" for k, v in asdict(self.spec).items() if k != "env_kwargs")
        return f"FastPolicy({kw})"


def load_pretrained(path: str | Path, manifest: str | Path | None = None, trust: bool = False) -> Any:
    """Load a shipped ``AmigoBot-v1`` agent (a fast-PPO zip as a :class:`FastPolicy`, or an SB3 PPO/SAC/TD3/A2C/DDPG
    zip) after checking the SHA-256 of its manifest (default ``<zip stem>.json``, with ``sha256`` and, for SB3,
    ``algo``). ``trust``: load an SB3 zip (a pickle) neither shipped nor written here. A learning rate stored as
    pickled code (ppo.zip's, by CPython 3.11: it crashes 3.13) is not run; it is 0. Raises ``FileNotFoundError`` (no
    zip or manifest), ``ValueError`` (no or another digest, an unknown algorithm), ``UntrustedFileError``."""
    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"load_pretrained: no model file {p}")
    m = Path(manifest) if manifest is not None else p.with_suffix(".json")
    if not m.is_file():
        raise FileNotFoundError(f"load_pretrained: no manifest {m} beside {p.name}")
    meta = json.loads(m.read_text())
    want = meta.get("sha256") if isinstance(meta, dict) else None
    if not isinstance(want, str) or len(want) != 64:
        raise ValueError(f"load_pretrained: manifest {m} has no sha256 (64 hex digits), got {want!r}")
    got = sha256_file(p)
    if got != want.lower():
        raise ValueError(f"load_pretrained: sha256 of {p} is {got}, the manifest {m.name} says {want}")
    with zipfile.ZipFile(p) as z:
        fast = "model.json" in z.namelist()
        coded = not fast and isinstance(json.loads(z.read("data")).get("learning_rate"), dict)
    if fast:
        return FastPolicy.load(p)
    algo = str(meta.get("algo", "")).lower()
    import stable_baselines3 as sb3

    classes: dict[str, Any] = {"ppo": sb3.PPO, "sac": sb3.SAC, "td3": sb3.TD3, "a2c": sb3.A2C, "ddpg": sb3.DDPG}
    if algo not in classes:
        raise ValueError(f"load_pretrained: manifest algo must be one of {sorted(classes)}, got {algo!r}")
    require_trust(p, got, trust)
    return classes[algo].load(str(p), device="cpu", custom_objects={"learning_rate": 0.0} if coded else None)
