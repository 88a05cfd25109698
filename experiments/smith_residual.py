"""A learned residual on the delay compensator: fast PPO's residual recipe with the Smith predictor of
``experiments/smith_delay.py`` (``SmithEstimated``, ``k = 2``, ``--quiet 1e-6``) as its base instead of the
analytic controller (issue 36, item 1).

    python experiments/smith_residual.py check                       # the base against smith_delay.py's, per step
    python experiments/smith_residual.py train -- <train-fast arguments>   # e.g. --out runs/sr_s0 --seed 0 ...
    python experiments/smith_residual.py val --models sr_s0=runs/sr_s0/model.zip [--seeds 20] [--cells ...]
    python experiments/smith_residual.py bench -- <amigo-gym benchmark arguments>   # the test cells, once

:class:`SmithBuilder` replaces :class:`amigo_gym.policies.learned.FeatureBuilder` in this process (the model zips it
writes need it: loaded without it, their networks' two more inputs make ``FastPolicy`` refuse them): the base action is
the compensator's, computed for all rows at once by the package's
:func:`amigo_gym.policies.compensator.predict_rows` (compiled) from the observation and a state per row
(the commands issued, read from the observation's ``previous_command`` fields; the seven candidate delays' simulated
``v``, ``omega`` and their squared mismatch); the features add the estimated delay [s] and whether the gain ``k = 2`` is
on (the quiet rule) to the recipe's. ``--gate``: the network's output counts only on the rows whose quiet flag is on
(elsewhere the action is the compensator's), in training (``train --gate``), for named models (``val --gate NAME``) or
all (``bench --gate``). ``--saturation step|hold --hold N`` (before the command): the gain ``k = 1`` on a step whose ``k
= 2`` command reaches a wheel's limit (``hold``: and the ``N`` steps after); ``--saturation sharp --kappa K``: ``k = 1``
while the curvature at H or at a preview point exceeds ``K`` [1/m]. ``check`` steps one episode per validation cell with
the base alone (the residual zero) beside ``SmithEstimated`` and prints the largest difference of their actions. ``val``
prints the validation cells' mean H RMS [mm] of the analytic controller, the compensator alone and each model, and their
ratios; ``bench`` is ``amigo-gym benchmark`` with these models (e.g. ``--suite 2.0 --agents analytic
'sr=experiments/candidates/sr_s*.zip' --out docs/benchmark/smith_residual``). Validation cells and seeds for every
decision (:mod:`amigo_gym.tools.training.protocol`).
"""

from __future__ import annotations

import argparse
import glob
import sys
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np

import amigo_gym.policies.learned as learned
import amigo_gym.tools.training.fastppo as fastppo
from amigo_gym.policies import AnalyticTrackingPolicy
from amigo_gym.policies import compensator as comp
from amigo_gym.policies.learned import FastPolicy, FeatureBuilder, FeatureSpec, RunningMeanStd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from smith_delay import CANDIDATES, SmithEstimated

GAIN, QUIET = 2.0, 1e-6  # the compensator chosen on the validation cells (baselines.md)
GATE: dict[str, Any] = {"on": False, "flags": None}
#: --saturation: "none"; "step": k = 1 on a step whose k = 2 command saturates the wheels; "hold": and ``hold``
#: steps on; "sharp": k = 1 while the curvature at H or at a preview point exceeds ``kappa`` [1/m] in magnitude
SATURATION: dict[str, Any] = {
    "rule": "none",
    "hold": 0,
    "kappa": 0.0,
}  # --gate: the correction only where the quiet flag is on
RING = comp.RING
N_CAND = len(CANDIDATES)


class SmithBuilder(FeatureBuilder):
    """:class:`FeatureBuilder` with the compensator's base action and two more features (module docstring); the
    state per row: the recipe's, then :func:`_smith_rows`'."""

    def __init__(self, spec: FeatureSpec) -> None:
        super().__init__(spec)
        if spec.residual_bound <= 0:
            raise ValueError("SmithBuilder: a residual (residual_bound > 0) is its only use")
        p = spec.params()
        if max(CANDIDATES) / p.dt + 2 > RING:
            raise ValueError(f"SmithBuilder: dt = {p.dt} s is too short for a ring of {RING} commands")
        self.p, r, a = p, p.robot, p.actuators
        self.fast_pol, self.slow_pol = AnalyticTrackingPolicy(p, GAIN), AnalyticTrackingPolicy(p, 1.0)
        names = self.fields.names
        self.col = np.array([names.index(f) for f in ("cross_track_error", "sin_heading_error", "cos_heading_error",
                             "curvature", "wheel_rate_1", "wheel_rate_2", "previous_command_1",
                             "previous_command_2")])  # fmt: skip
        self.rob = np.array([r.r1, r.r2, r.l1, r.l3, r.max_wheel_rate, a.acceleration, a.deceleration,
                             a.rot_acceleration, a.rot_deceleration])  # fmt: skip
        self.cand = np.array(CANDIDATES)
        self.curv_cols = np.array([i for i, f in enumerate(names) if f == "curvature" or f.startswith("preview_curv")])
        self.base_state = self.state_dim
        self.state_dim += 1 + 2 * RING + 3 * N_CAND + 1  # + the steps left at k = 1 after a saturation
        self.dim += 2

    def __call__(self, obs: Any, state: Any, starts: Any) -> tuple[Any, Any, Any]:
        n, b = obs.shape[0], self.base_state
        feats, _, s_base = super().__call__(obs, state[:, :b], starts)  # the recipe's features (analytic base)
        st = np.array(state[:, b:], dtype=np.float64)
        delay, dist, pred = comp._predictor()(obs, np.asarray(starts, dtype=np.bool_), st[:, :-1], self.col,
                                                     self.cand, self.rob, self.p.dt, self.p.error_scale)  # fmt: skip
        fast = dist <= QUIET
        seen = np.array(obs, dtype=np.float64)
        seen[:, self.col[0]] = pred[:, 0] / self.p.error_scale
        seen[:, self.col[1]], seen[:, self.col[2]] = np.sin(pred[:, 1]), np.cos(pred[:, 1])
        z = np.where(starts, 0.0, state[:, 0]).reshape(n, 1)
        a_f, z_f = self.fast_pol.predict(seen, state=z, episode_start=None)
        a_s, z_s = self.slow_pol.predict(seen, state=z, episode_start=None)
        if SATURATION["rule"] == "sharp":
            curv = np.abs(obs[:, self.curv_cols]).max(axis=1)  # |kappa| l3, clipped to 1
            fast = fast & ~(curv > SATURATION["kappa"] * self.p.robot.l3)
        elif SATURATION["rule"] != "none":  # the k = 2 command at a wheel's limit: k = 1 (and for ``hold`` steps on)
            sat = np.abs(a_f).max(axis=1) >= 1.0 - 1e-9
            hold = np.where(sat, float(SATURATION["hold"]), np.maximum(np.where(starts, 0.0, st[:, -1]) - 1.0, 0.0))
            fast = fast & ~sat & (hold <= 0.0)
            st[:, -1] = hold
        base = np.where(fast[:, None], a_f, a_s).astype(np.float64)
        s_base[:, 0] = np.where(fast, z_f[:, 0], z_s[:, 0])
        feats = feats.copy()
        feats[:, -2:] = base
        feats = np.concatenate([feats, delay[:, None], fast[:, None].astype(np.float64)], axis=1)
        GATE["flags"] = fast  # for the env_action that follows this call (rollout, FastPolicy._act)
        return feats, base, np.concatenate([s_base, st], axis=1)


_env_action = learned.env_action


def gated_env_action(u: Any, base: Any, prev: Any, residual_bound: float, filter_alpha: float, mask: Any = None) -> Any:
    """:func:`amigo_gym.policies.learned.env_action` with the network's output zeroed on the rows whose quiet flag
    is off when ``GATE["on"]`` (the action there: the compensator's)."""
    if GATE["on"] and GATE["flags"] is not None and residual_bound > 0:
        u = np.where(GATE["flags"][:, None], u, 0.0)
    return _env_action(u, base, prev, residual_bound, filter_alpha, mask)


class Gated:
    """A model acting with ``GATE["on"]`` (its correction only where the quiet flag is on)."""

    def __init__(self, policy: FastPolicy) -> None:
        self.policy = policy

    def predict(self, *a: Any, **k: Any) -> Any:
        GATE["on"] = True
        try:
            return self.policy.predict(*a, **k)
        finally:
            GATE["on"] = False

    def reset(self) -> None:
        self.policy.reset()


def install() -> None:
    """Make every fast-PPO model and run in this process use :class:`SmithBuilder` (and the gate, when on)."""
    learned.FeatureBuilder = SmithBuilder  # type: ignore[misc]
    fastppo.FeatureBuilder = SmithBuilder  # type: ignore[misc]
    learned.env_action = gated_env_action
    fastppo.env_action = gated_env_action


def compensator(env_kwargs: dict[str, Any]) -> FastPolicy:
    """The compensator alone: a residual policy whose network outputs 0."""
    spec = FeatureSpec(env_kwargs, history=4, residual_bound=0.3)
    dim = SmithBuilder(spec).dim
    layers = [(np.zeros((dim, 2)), np.zeros(2))]
    return FastPolicy(spec, layers, np.zeros(2), RunningMeanStd.zeros(dim))


def check() -> None:
    """Per validation cell, one episode (the first validation seed): the base alone against ``SmithEstimated``."""
    from amigo_gym.tools.training.protocol import VALIDATION_SEEDS, validation_cells

    for sc in validation_cells("AmigoBot-v1", 1):
        kw = dict(sc.env_kwargs)
        env_a, env_b = gym.make(sc.env_id, **kw), gym.make(sc.env_id, **kw)
        ref = SmithEstimated(env_a.unwrapped.params, GAIN, QUIET)  # type: ignore[attr-defined]
        pol = compensator(kw)
        oa, _ = env_a.reset(seed=VALIDATION_SEEDS[0])
        ob, _ = env_b.reset(seed=VALIDATION_SEEDS[0])
        worst, state, h_a, h_b = 0.0, None, [], []
        for t in range(sc.max_steps):
            a = ref.act(oa, t == 0)
            b, state = pol.predict(ob[None], state=state, episode_start=np.array([t == 0]), deterministic=True)
            b = np.asarray(b, dtype=np.float32).reshape(-1)
            worst = max(worst, float(np.abs(a - b).max()))
            oa, _, ta, ua, ia = env_a.step(a)
            ob, _, tb, ub, ib = env_b.step(b)
            h_a.append(ia["cross_track_error"])
            h_b.append(ib["cross_track_error"])
            if ta or ua or tb or ub:
                break
        rms = [1e3 * float(np.sqrt(np.mean(np.square(h)))) for h in (h_a, h_b)]
        print(f"{sc.name}: {t + 1} steps, largest action difference {worst:.1e}, H RMS {rms[0]:.6f} / {rms[1]:.6f} mm")


def _models(items: list[str], gated: list[str]) -> list[tuple[str, Any]]:
    """``NAME=ZIP`` (a glob: ``NAME_0``, ...) models; ``NAME`` in ``gated`` (``--gate``): acting with the gate."""
    out: list[tuple[str, Any]] = []
    for m in items:
        name, pattern = m.split("=", 1)
        paths = sorted(glob.glob(pattern)) or [pattern]
        for i, path in enumerate(paths):
            pol = FastPolicy.load(path)
            out.append((name if len(paths) == 1 else f"{name}_{i}", Gated(pol) if name in gated else pol))
    return out


def val(a: argparse.Namespace) -> None:
    """The validation table (module docstring)."""
    from amigo_gym.tools.machine import machine_line
    from amigo_gym.tools.training.benchmark import evaluate, make_env
    from amigo_gym.tools.training.protocol import validation_cells

    models = _models(a.models, a.gate)
    print(machine_line())
    names = ["analytic", "compensator"] + [n for n, _ in models]
    print("| cell | " + " | ".join(f"{n} [mm]" for n in names) + " | " +
          " | ".join(f"{n}/analytic" for n in names[1:]) + " |")  # fmt: skip
    print("|---" * (2 * len(names)) + "|")
    rows: list[tuple[str, list[float]]] = []
    for sc in validation_cells("AmigoBot-v1", a.seeds):
        if a.cells and sc.name not in a.cells:
            continue
        env = make_env(sc)
        p = env.unwrapped.params if hasattr(env, "unwrapped") else env.params
        agents = [AnalyticTrackingPolicy(p), compensator(dict(sc.env_kwargs))] + [m for _, m in models]
        means = [float(np.mean([1e3 * e["h_rms_m"] for e in evaluate(ag, env, sc)])) for ag in agents]
        env.close()
        print(f"| {sc.name} | " + " | ".join(f"{m:.2f}" for m in means) + " | " +
              " | ".join(f"{m / means[0]:.3f}" for m in means[1:]) + " |", flush=True)  # fmt: skip
        rows.append((sc.name, [m / means[0] for m in means[1:]]))
    if a.plot:
        plot(rows, names[1:], a.plot, a.seeds)


def plot(rows: list[tuple[str, list[float]]], names: list[str], path: str, seeds: int) -> None:
    """Grouped bars: each agent's ratio to the analytic controller per validation cell, 1 and 0.8 marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(10, 4.5))
    width = 0.8 / len(names)
    for j, name in enumerate(names):
        ax.bar(np.arange(len(rows)) + (j - (len(names) - 1) / 2) * width, [r[1][j] for r in rows], width, label=name)
    ax.axhline(1.0, color="k", lw=0.8)
    ax.axhline(0.8, color="k", lw=0.8, ls="--", label="20 % below the analytic controller")
    ax.set_xticks(np.arange(len(rows)), [r[0].removeprefix("val_") for r in rows], rotation=30, ha="right")
    ax.set_ylabel("mean H RMS / analytic controller's")
    ax.set_title(f"Validation cells, {seeds} seeds each (experiments/smith_residual.py val)")
    ax.legend(fontsize=8, ncol=3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def _record_command(command: str) -> None:
    """Make ``amigo-gym benchmark``'s outputs in this process record ``command`` (this script's), not its own."""
    from amigo_gym.tools.training import benchmark

    def fix(doc: Any) -> Any:
        return {**doc, "command": command} if isinstance(doc, dict) and "command" in doc else doc

    write_outputs, write_json = benchmark.write_outputs, benchmark.atomic_write_json
    benchmark.write_outputs = lambda doc, *a, **k: write_outputs(fix(doc), *a, **k)  # type: ignore[assignment]
    benchmark.atomic_write_json = lambda path, doc, *a, **k: write_json(path, fix(doc), *a, **k)  # type: ignore[assignment]


def main() -> int:
    install()
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--saturation", choices=("none", "step", "hold", "sharp"), default="none", help="SATURATION's rule")
    p.add_argument("--kappa", type=float, default=0.0, help="with --saturation sharp: the curvature limit [1/m]")
    p.add_argument("--hold", type=int, default=0, help="with --saturation hold: steps at k = 1 after a saturation")
    sub = p.add_subparsers(dest="cmd", required=True)
    sub.add_parser("check")
    t = sub.add_parser("train")
    t.add_argument("--gate", action="store_true", help="train with the correction only where the quiet flag is on")
    t.add_argument("rest", nargs=argparse.REMAINDER)
    v = sub.add_parser("val")
    v.add_argument("--models", nargs="*", default=[])
    v.add_argument("--seeds", type=int, default=20)
    v.add_argument("--cells", nargs="*", default=None)
    v.add_argument("--gate", nargs="*", default=[], help="model names that act with the gate")
    v.add_argument("--plot", default=None, help="write the ratios as a bar chart (PNG) here")
    b = sub.add_parser("bench")
    b.add_argument("--gate", action="store_true", help="every model acts with the gate")
    b.add_argument("rest", nargs=argparse.REMAINDER)
    a = p.parse_args()
    SATURATION.update(rule=a.saturation, hold=a.hold, kappa=a.kappa)
    if a.cmd == "check":
        check()
    elif a.cmd in ("train", "bench"):
        from amigo_gym.tools.training import benchmark

        GATE["on"] = a.gate
        rest = [x for x in a.rest if x != "--"]
        if a.cmd == "train":
            return fastppo.main(rest)
        sat = "" if a.saturation == "none" else f"--saturation {a.saturation} --hold {a.hold} --kappa {a.kappa:g} "
        _record_command(
            f"python experiments/smith_residual.py {sat}bench {'--gate ' if a.gate else ''}-- " + " ".join(rest)
        )
        return benchmark.main(rest)
    else:
        val(a)
    return 0


if __name__ == "__main__":
    sys.exit(main())
