"""One place holds each speed figure (docs/performance.md); the README's table is generated from the benchmark JSON.

The README's performance table must be exactly what ``amigo-gym bench-env --table-from`` prints from the committed
run (docs/figures/bench_env.json, bench_core.json), so a new run changes both or the test fails; the other pages
(env card, development) carry no copy of those figures and link to performance.md instead.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

from amigo_gym.tools.bench.env import headline_table

ROOT = Path(__file__).resolve().parents[1]
ENV_JSON = ROOT / "docs/figures/bench_env.json"
CORE_JSON = ROOT / "docs/figures/bench_core.json"


def _readme_table() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    lines = text.split("## Performance", 1)[1].splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.startswith("|"))
    rows = []
    for ln in lines[start:]:
        if not ln.startswith("|"):
            break
        rows.append(ln)
    return "\n".join(rows) + "\n"


def test_readme_performance_table_is_generated_from_the_committed_json() -> None:
    generated = headline_table(json.loads(ENV_JSON.read_text()), json.loads(CORE_JSON.read_text()))
    assert _readme_table() == generated
    command = "amigo-gym bench-env --table-from docs/figures/bench_env.json --core-json docs/figures/bench_core.json"
    assert command in (ROOT / "README.md").read_text(encoding="utf-8")
    # docs/performance.md shows the same generated table, with its command
    performance = (ROOT / "docs/performance.md").read_text(encoding="utf-8")
    assert generated in performance and command in performance


def test_the_table_command_prints_it() -> None:
    r = subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "bench-env", "--table-from", str(ENV_JSON), "--core-json",
         str(CORE_JSON)],
        cwd=ROOT, capture_output=True, text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)},
    )  # fmt: skip
    assert r.returncode == 0, r.stderr
    assert r.stdout == _readme_table()
    bad = subprocess.run(
        [sys.executable, "-m", "amigo_gym.tools.cli", "bench-env", "--table-from", str(CORE_JSON)],
        cwd=ROOT, capture_output=True, text=True, timeout=120, env={**os.environ, "PYTHONPATH": str(ROOT)},
    )  # fmt: skip
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1, bad.stderr


def test_other_pages_link_to_performance_md_instead_of_copying_figures() -> None:
    for page in ("docs/env_card.md", "docs/development.md"):
        text = (ROOT / page).read_text(encoding="utf-8")
        assert "performance.md" in text, page
        # no measured speed figure: no steps/s or us-per-step table rows, no ratio against a peer
        assert not re.search(r"^\|.*(steps/s|\[us\]|µs|CartPoleVectorEnv \[).*\|$", text, flags=re.MULTILINE), page
        assert not re.search(r"\d\.\d+×|\d\.\d+x\b", text), page


def test_readme_v1_table_is_generated_from_the_benchmark_json() -> None:
    from amigo_gym.tools.training.benchmark import readme_table

    doc = json.loads((ROOT / "docs/benchmark/benchmark.json").read_text())
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert readme_table(doc) in text
    assert "amigo-gym benchmark --table-from docs/benchmark/benchmark.json" in text
