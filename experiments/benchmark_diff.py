"""Are two benchmark.json files the same on the agents they share? Exact comparison, no tolerance.

    git show 8f0a874:docs/benchmark/benchmark.json > old.json
    python experiments/benchmark_diff.py old.json docs/benchmark/benchmark.json

For the agents both documents ran, compares with ``==`` on the parsed JSON (floats are written by ``json`` as
their shortest round-tripping repr, so equal parsed floats are equal bits): every ``results`` record (per-episode
lists included), ``aggregates``, ``performance_profiles`` (and their thresholds), the ``agents`` entries (without
``path``, the checkout the run was made from, and the manifests' ``claimed`` block, which the run's own claims
write after it), ``unavailable``, ``scenarios`` and ``feasibility``. Prints the agents only one side has and one
line per comparison; exit status 0 when everything shared is identical, 1 otherwise.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any


def _agent_entry(a: dict[str, Any]) -> dict[str, Any]:
    a = {k: v for k, v in a.items() if k != "path"}
    if isinstance(a.get("manifest"), dict):
        a["manifest"] = {k: v for k, v in a["manifest"].items() if k != "claimed"}
    return a


def compare(old: dict[str, Any], new: dict[str, Any]) -> tuple[list[str], bool]:
    """Lines of the report and whether every shared item is identical."""
    shared = [a for a in old["aggregates"] if a in new["aggregates"]]
    lines = [
        f"agents in both: {', '.join(shared)}",
        f"only in the first: {', '.join(a for a in old['aggregates'] if a not in new['aggregates']) or '-'}",
        f"only in the second: {', '.join(a for a in new['aggregates'] if a not in old['aggregates']) or '-'}",
    ]
    ok = True

    def check(what: str, same: bool) -> None:
        nonlocal ok
        ok &= same
        lines.append(f"{what}: {'identical' if same else 'DIFFERENT'}")

    def key(r: dict[str, Any]) -> tuple[Any, ...]:
        return (r["agent"], r["seed"], r["scenario"])

    ro = {key(r): r for r in old["results"] if r["agent"] in shared}
    rn = {key(r): r for r in new["results"] if r["agent"] in shared}
    differ = [k for k in ro if k in rn and ro[k] != rn[k]]
    check(
        f"results records of the shared agents ({len(ro)} and {len(rn)}; {len(differ)} differ)",
        not differ and ro.keys() == rn.keys(),
    )
    check("aggregates", all(old["aggregates"][a] == new["aggregates"][a] for a in shared))
    po, pn = old["performance_profiles"], new["performance_profiles"]
    check(
        "performance profiles",
        po["taus_m"] == pn["taus_m"] and all(po["agents"].get(a) == pn["agents"].get(a) for a in shared),
    )
    ao = [_agent_entry(a) for a in old["agents"] if a["agent"] in shared]
    an = [_agent_entry(a) for a in new["agents"] if a["agent"] in shared]
    check(f"agents entries ({len(ao)}; without path and manifest.claimed)", ao == an)
    uo = [u for u in old["unavailable"] if u.get("agent") in shared or u.get("agent") is None]
    un = [u for u in new["unavailable"] if u.get("agent") in shared or u.get("agent") is None]
    check(f"unavailable pairs ({len(uo)})", uo == un)
    check("scenarios", old["scenarios"] == new["scenarios"])
    check("feasibility", old["feasibility"] == new["feasibility"])
    lines.append(f"wall_time_s {old.get('wall_time_s')} and {new.get('wall_time_s')}")
    return lines, ok


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("first", type=Path, help="a benchmark.json [file]")
    ap.add_argument("second", type=Path, help="another benchmark.json [file]")
    args = ap.parse_args(argv)
    lines, ok = compare(json.loads(args.first.read_text()), json.loads(args.second.read_text()))
    print("\n".join(lines))
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
