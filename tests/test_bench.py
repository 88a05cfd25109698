"""Smoke tests of the benchmarks (they run and report every section; no timing is asserted)."""

from __future__ import annotations

import importlib.util
import json
import os
import sys
from pathlib import Path
from types import ModuleType

import pytest

from amigo_gym.tools.bench import core, env


def _render_trail() -> ModuleType:
    """``experiments/render_trail.py``, imported by its path (registered, as its dataclass needs)."""
    path = Path(__file__).resolve().parents[1] / "experiments" / "render_trail.py"
    spec = importlib.util.spec_from_file_location("render_trail", path)
    assert spec is not None and spec.loader is not None
    mod = sys.modules.setdefault("render_trail", importlib.util.module_from_spec(spec))
    spec.loader.exec_module(mod)
    return mod


def test_measure_many_times_every_function() -> None:
    calls = {"a": 0, "b": 0}

    def a() -> None:
        calls["a"] += 1

    def b() -> None:
        calls["b"] += 1

    t = core.measure_many({"a": a, "b": b}, repeats=3, min_time=0.001)
    assert set(t) == {"a", "b"} and all(v > 0 for v in t.values())
    assert calls["a"] >= 5 and calls["b"] >= 5


def test_bench_env_quick_reports_every_section(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("stable_baselines3")
    pytest.importorskip("matplotlib")
    out, png = tmp_path / "bench.json", tmp_path / "fig" / "vector.png"
    argv = ["--quick", "--sizes", "1", "4", "--v1", "--ppo-envs", "2", "--json", str(out), "--plot", str(png)]
    assert env.main(argv) == 0
    cap = capsys.readouterr()
    for text in ("Pendulum-v1", "native / CartPole", "fixed cost", "memory per sub-env", "SB3 PPO", "AmigoBot-v1"):
        assert text in cap.out
    assert "N = 4" in cap.err  # progress on stderr
    doc = json.loads(out.read_text())
    assert [r["n"] for r in doc["vector"]] == [1, 4]
    assert all(r["sync"] > 0 and r["native"] > 0 and r["cartpole"] > 0 for r in doc["vector"])
    assert set(doc["vector"][0]["kernels"]) <= {"numpy", "numba", "numba-parallel"}
    assert doc["fixed_cost_n1"]["cartpole_us"] > 0
    assert doc["memory"]["n"] >= 2 and doc["memory"]["amigobot_retained"] > 0
    assert [r["n_envs"] for r in doc["ppo"]][:2] == [1, 2] and all(r["ratio"] > 0 for r in doc["ppo"])
    assert (doc["v1"] is None) == any("AmigoBot-v1" in n for n in doc["notes"])
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bench_env_refuses_bad_arguments(capsys: pytest.CaptureFixture[str]) -> None:
    assert env.main(["--quick", "--memory-n", "1", "--skip-single", "--skip-vector", "--skip-ppo"]) == 2
    assert "memory_n" in capsys.readouterr().err
    assert env.main(["--quick", "--threads", "0", "--skip-single", "--skip-vector", "--skip-ppo"]) == 2
    assert "threads" in capsys.readouterr().err


def test_bench_env_kernels_and_targets(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """``--kernels`` times each step implementation; the targets table names the CPU and judges each ratio."""
    pytest.importorskip("numba")
    from amigo_gym.tools.machine import cpu_model

    out = tmp_path / "bench.json"
    argv = ["--quick", "--sizes", "1", "8", "--skip-memory", "--skip-ppo", "--v1", "--kernels", "--threads", "1"]
    assert env.main([*argv, "--json", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "1 thread(s)" in printed.splitlines()[0] and "load average" in printed.splitlines()[0]
    assert f"| speed targets on {cpu_model()} (SIMD " in printed and "kernel=numba-parallel" in printed
    doc = json.loads(out.read_text())
    assert doc["machine"]["numba"].startswith("numba ") and doc["machine"]["load_average"]["end"]
    want = {(e, n) for e in ("AmigoBot-v0", "AmigoBot-v1") for n in (0, 8)}
    assert {(r["env_id"], r["n"]) for r in doc["kernels"]} == want
    for r in doc["kernels"]:
        assert r["speedup"] == pytest.approx(r["us"]["numpy"] / r["us"]["numba"])
        assert ("numba-parallel" in r["us"]) == (r["n"] > 0)
    names = [t["name"] for t in doc["targets"]]
    assert names == ["single", "call_n1", "v1_v0"]  # no N = 4096 in this run
    single = doc["targets"][0]
    assert single["ratio"] == pytest.approx(doc["single"]["amigobot_us"] / doc["single"]["pendulum_us"])
    assert single["met"] == (single["ratio"] <= 0.4)


def test_targets_judge_each_ratio_against_its_bound() -> None:
    """:func:`env.targets` on hand-made results: the ratios, the bounds of the speed targets, met or not."""
    rows = [
        env.vector_row(1, native=1e5, cartpole=2e4),  # call: 10 us against 50 us -> 0.2, met
        env.vector_row(4096, native=3e6, cartpole=6e6, kernels={"numba-parallel": 9e6}),
    ]
    v1 = {"ratio": 3.0, "vector": {"4096": {"v1": 1e6, "v0": 2e6}}}
    doc = {"single": {"ratio": 0.4}, "vector": rows, "v1": v1}
    got = {t["name"]: (round(t["ratio"], 6), t["met"]) for t in env.targets(doc)}
    assert got == {
        "single": (0.4, True),
        "vector_4096": (0.5, False),
        "vector_4096_threads": (1.5, None),
        "call_n1": (0.2, True),
        "v1_v0": (3.0, False),
        "v1_v0_vector": (2.0, None),
    }


def test_bench_core_quick(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "core.json"
    assert core.main(["--quick", "--skip-startup", "--threads", "1", "--json", str(out)]) == 0
    assert "kernel/step_columns" in capsys.readouterr().out
    doc = json.loads(out.read_text())
    assert [r["n"] for r in doc["rows"]] == [1, 64]
    from amigo_gym.sim.fast_v1 import numba_available

    if numba_available():
        assert all(r["kernel"] > 0 and r["kernel_par"] > 0 for r in doc["rows"])


def test_bench_core_startup_rows_name_both_routes() -> None:
    """The start-up table has the reference's first step (no numba) beside the compiled one's, and the
    reference's snippets are the compiled ones with only the kernel changed."""
    for code in (core._FIRST_STEP, core._FIRST_STEP_V1):
        ref = core._numpy_route(code)
        assert "kernel='numpy'" in ref and "numba" not in ref and ref.replace("numpy'", "numba'") == code
    keys = ("import_s", "python_s", "kernel_cold_s", "kernel_warm_s", "v1_cold_s", "v1_warm_s", "numba_import_s")
    st = {**dict(zip(keys, (0.5, 0.02, 3.0, 0.8, 4.0, 0.9, 0.7), strict=True)), "numpy_first_s": 0.6}
    st["v1_numpy_first_s"] = 0.65
    table = core.format_table([], st)
    assert '| python -c "import amigo_gym, numba" | 0.700 |' in table
    assert "| import + first v0 vector step, kernel=numpy (no numba) | 0.600 |" in table
    assert "| import + first AmigoBot-v1 step, kernel=numpy | 0.650 |" in table


def test_simd_level_agrees_with_the_kernels_cpu_flags() -> None:
    """``simd_level`` (numpy's run-time detection) against the flags the kernel lists in /proc/cpuinfo."""
    from amigo_gym.tools.machine import cpu_model, machine_line, simd_level

    level = simd_level()
    line = machine_line()
    assert cpu_model() in line and f"SIMD {level}" in line
    try:
        text = Path("/proc/cpuinfo").read_text()
    except OSError:
        return  # not Linux: nothing independent to compare with
    flags = set()
    for row in text.splitlines():
        if row.lower().startswith(("flags", "features")):
            flags |= set(row.split(":", 1)[1].split())
    restricted = os.environ.get("NPY_DISABLE_CPU_FEATURES", "").split()
    if "avx512f" in flags and "X86_V4" in restricted:  # numpy's AVX2 code on an AVX-512 machine (numpy >= 2.4's names)
        assert level == "AVX2", (level, restricted)
    elif "avx512f" in flags:
        assert level.startswith("AVX-512"), (level, sorted(f for f in flags if "avx" in f))
    elif "avx2" in flags:
        assert level == "AVX2"
    elif "asimd" in flags:
        assert level in ("NEON (ASIMD)", "SVE")


@pytest.mark.parametrize(
    ("cls", "bad"),
    [
        (core.CoreSettings, {"repeats": 0}),
        (core.CoreSettings, {"sizes": (1, 0)}),
        (env.EnvSettings, {"min_time": float("nan")}),
        (env.EnvSettings, {"ppo_envs": 5000}),
    ],
)
def test_bench_settings_refuse_a_bad_value_in_one_line(cls: type, bad: dict[str, object]) -> None:
    """Every benchmark's settings dataclass checks its ranges itself (command line or not): one line naming the
    field, the allowed range and the value."""
    name, value = next(iter(bad.items()))
    with pytest.raises(ValueError) as exc:
        cls(**bad)
    text = str(exc.value)
    assert "\n" not in text and name in text and "must be" in text and str(value if name != "sizes" else 0) in text


def test_bench_options_come_from_the_settings(capsys: pytest.CaptureFixture[str]) -> None:
    """The parsers are derived from the settings dataclasses: the defaults parsed from an empty command line are the
    dataclass's, the help text of ``--sizes`` names the default the code uses, and a refused value is one line and
    status 2 (not a traceback), also for the commands run as modules."""
    from dataclasses import fields

    from amigo_gym.tools.bench import train
    from amigo_gym.tools.options import OneLineParser, add_dataclass_options, attribute_help, settings_from_args

    render_trail = _render_trail()
    for cls in (core.CoreSettings, env.EnvSettings, render_trail.RenderTrailSettings):
        p = OneLineParser(prog="x")
        add_dataclass_options(p, cls)
        assert settings_from_args(cls, p.parse_args([])) == cls()
        assert {a.dest for a in p._actions} - {"help"} == {f.name for f in fields(cls)}
    assert str(core.DEFAULT_SIZES) in attribute_help(core.CoreSettings)["sizes"]
    assert str(env.DEFAULT_SIZES) in attribute_help(env.EnvSettings)["sizes"]
    assert str(env.QUICK_SIZES) in attribute_help(env.EnvSettings)["quick"]
    assert train.TrainSettings(offpolicy=" sac, tqc ,").offpolicy_algos == ["sac", "tqc"]
    for main, argv, name in (
        (render_trail.main, ["--n", "0", "--skip-memory", "--skip-time"], "--n"),
        (train.main, ["--offpolicy", "ddpg"], "offpolicy"),
    ):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and name in err and "error:" in err
