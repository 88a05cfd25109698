"""A learned residual on the delay compensator: fast PPO's residual recipe with the Smith predictor of
``experiments/smith_delay.py`` (``SmithEstimated``, ``k = 2``, ``--quiet 1e-6``) as its base instead of the
analytic controller (issue 36, item 1).

    python experiments/smith_residual.py check                       # the base against smith_delay.py's, per step
    python experiments/smith_residual.py train -- <train-fast arguments>   # e.g. --out runs/sr_s0 --seed 0 ...
    python experiments/smith_residual.py val --models sr_s0=runs/sr_s0/model.zip [--seeds 20] [--cells ...]
    python experiments/smith_residual.py bench -- <amigo-gym benchmark arguments>   # the test cells, once

:class:`SmithBuilder` replaces :class:`amigo_gym.policies.learned.FeatureBuilder` in this process: the package's
builder for a residual on :class:`amigo_gym.policies.DelayCompensatedPolicy` (``FeatureSpec(base="compensator",
residual_gain=2)``), which the candidate zips written here before the package had it need (their specs say
``base="analytic"``; loaded elsewhere, ``FastPolicy`` refuses them: their networks take two inputs more).
``--gate``: the network's output counts only on the rows whose quiet flag is on
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
import dataclasses
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
from smith_delay import SmithEstimated

GAIN, QUIET = 2.0, 1e-6  # the compensator chosen on the validation cells (docs/experiments.md)
#: the gate for builders made inside the package's code (``train --gate``, ``bench --gate``)
GATE: dict[str, bool] = {"on": False}
#: --saturation: "none"; "step": k = 1 on a step whose k = 2 command saturates the wheels; "hold": and ``hold``
#: steps on; "sharp": k = 1 while the curvature at H or at a preview point exceeds ``kappa`` [1/m] in magnitude
SATURATION: dict[str, Any] = {"rule": "none", "hold": 0, "kappa": 0.0}


class Saturating(comp.DelayCompensatedPolicy):
    """The package's compensator with :data:`SATURATION`'s rule as well deciding where ``k = 1``; its state: the
    package's, then the steps left at ``k = 1`` after a saturation."""

    def __init__(self, params: Any, gain: float) -> None:
        super().__init__(params, gain, QUIET)
        names = self._fields.names
        self.curv_cols = np.array([i for i, f in enumerate(names) if f == "curvature" or f.startswith("preview_curv")])
        self.state_dim += 1

    def compensate(self, obs: Any, state: Any, starts: Any) -> tuple[Any, Any, Any, Any]:
        """:meth:`DelayCompensatedPolicy.compensate`, the gain chosen by the quiet flag and the rule."""
        p, st = self.params, np.array(state[:, 1:-1], dtype=np.float64)
        delay, dist, pred = comp._predictor()(obs, starts, st, self._col, np.array(comp.CANDIDATES), self._rob, p.dt,
                                              p.error_scale)  # fmt: skip
        seen = np.array(obs, dtype=np.float64)
        seen[:, self._col[0]] = pred[:, 0] / p.error_scale
        seen[:, self._col[1]], seen[:, self._col[2]] = np.sin(pred[:, 1]), np.cos(pred[:, 1])
        z = np.where(starts, 0.0, state[:, 0])
        (v_f, om_f, z_f), (v_s, om_s, z_s) = self.fast.command(seen, z), self.slow.command(seen, z)
        a_f, a_s = comp.limit_wheel_rates(v_f, om_f, p), comp.limit_wheel_rates(v_s, om_s, p)
        fast, hold = dist <= self.quiet, np.zeros(len(z))
        if SATURATION["rule"] == "sharp":
            fast &= ~(np.abs(obs[:, self.curv_cols]).max(axis=1) > SATURATION["kappa"] * p.robot.l3)  # |kappa| l3
        elif SATURATION["rule"] != "none":  # the k = 2 command at a wheel's limit: k = 1 (and for ``hold`` steps on)
            sat = np.abs(a_f.astype(np.float32)).max(axis=1) >= 1.0 - 1e-9
            hold = np.where(sat, float(SATURATION["hold"]), np.maximum(np.where(starts, 0.0, state[:, -1]) - 1.0, 0.0))
            fast &= ~sat & (hold <= 0.0)
        new_state = np.concatenate([np.where(fast, z_f, z_s)[:, None], st, hold[:, None]], axis=1)
        return np.where(fast[:, None], a_f, a_s), delay, fast.astype(np.float64), new_state


class SmithBuilder(FeatureBuilder):
    """The package's :class:`FeatureBuilder` for a residual on the compensator (``base="compensator"``, gain
    :data:`GAIN`, ``gate`` as given or :data:`GATE`) whatever the spec says (the candidate zips written before the
    package had it say ``base="analytic"``), its compensator :class:`Saturating` under a ``--saturation`` rule."""

    def __init__(self, spec: FeatureSpec, gate: bool | None = None) -> None:
        on = GATE["on"] if gate is None else gate
        super().__init__(dataclasses.replace(spec, base="compensator", residual_gain=GAIN, gate=on))
        if SATURATION["rule"] != "none":
            self.compensator = Saturating(self.spec.params(), GAIN)
            self.base_dim = self.compensator.state_dim
            self.state_dim = self.base_dim + self.spec.history * len(learned.HISTORY_FIELDS)


def acting_gated(policy: FastPolicy) -> FastPolicy:
    """``policy`` acting with the gate (its correction only where the quiet flag is on)."""
    policy.builder = SmithBuilder(policy.spec, gate=True)
    return policy


def install() -> None:
    """Make every fast-PPO model and run in this process use :class:`SmithBuilder`."""
    learned.FeatureBuilder = SmithBuilder  # type: ignore[misc]
    fastppo.FeatureBuilder = SmithBuilder  # type: ignore[misc]


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
            out.append((name if len(paths) == 1 else f"{name}_{i}", acting_gated(pol) if name in gated else pol))
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
