"""The package's import structure, read from its source with ``ast``: modules, imports, layers, circles.

:data:`LAYERS` is the architecture of docs/architecture.md as data, from the bottom up. Every import of one
``amigo_gym`` module by another (at module level or inside a function: both run) must point to the same layer
or a lower one; ``tests/test_layout.py`` asserts that, that no circle of modules exists, that no module of the
environment core (outside :data:`TOOLS`) imports the tools layer, and that the package's root holds at most
:data:`MAX_ROOT_MODULES` modules.

    python tests/layout.py                                   # the layers, their modules and lines, any breach
    python tests/layout.py --plot docs/figures/layers.png    # the picture of docs/architecture.md
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections import defaultdict
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "amigo_gym"
MAX_ROOT_MODULES = 8
#: the tools layer (training, benchmarks, sweeps, figures, the CLI); every other module is the environment core
TOOLS = "amigo_gym.tools"
#: the ``amigo-gym`` command, imported by nothing
CLI = "amigo_gym.tools.cli"

#: (layer, what it holds, module prefixes) from the bottom up; a module belongs to its longest matching prefix
LAYERS: list[tuple[str, str, tuple[str, ...]]] = [
    ("base", "files, package data", ("amigo_gym.io", "amigo_gym.data")),
    (
        "model",
        "the robot: parameters, kinematics, Fresnel integrals, actuators, randomisation",
        ("amigo_gym.model",),
    ),
    ("registry", "import amigo_gym: the registered env ids", ("amigo_gym",)),
    ("paths", "where H goes: path families, user paths, robot logs", ("amigo_gym.paths", "amigo_gym.logs")),
    ("task", "errors, observation, reward, end; the analytic inverse solution", ("amigo_gym.task",)),
    ("sim", "the compiled step (numba)", ("amigo_gym.sim",)),
    ("envs", "Gymnasium single and vector envs, rendering", ("amigo_gym.envs",)),
    ("policies", "controllers and learned policies", ("amigo_gym.policies",)),
    (
        "tools",
        "the tools layer's base: run folders, command-line helpers, the D-H derivation (sympy)",
        ("amigo_gym.tools",),
    ),
    ("training", "training, evaluation, benchmark, sweeps", ("amigo_gym.tools.training",)),
    ("analysis", "analysis, figures and speed benchmarks", ("amigo_gym.tools.analysis", "amigo_gym.tools.bench")),
    ("cli", "the amigo-gym command (imported by nothing)", ("amigo_gym.tools.cli",)),
]


def modules(package: Path = PACKAGE) -> dict[str, Path]:
    """``{dotted name: file}`` of every module of the package (a package's ``__init__`` under the package name)."""
    out = {}
    for f in sorted(package.rglob("*.py")):
        parts = f.relative_to(package.parent).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        if parts[-1] == "__main__":
            continue
        out[".".join(parts)] = f
    return out


def imports(mods: dict[str, Path]) -> dict[str, set[str]]:
    """``{module: the package modules it imports}``; ``from P import name`` counts P.name when that is a module, and
    ``importlib.import_module("...")`` / ``__import__("...")`` with a literal name count as imports."""

    def resolve(name: str) -> str:
        while name and name not in mods:
            name = name.rpartition(".")[0]
        return name

    out: dict[str, set[str]] = {m: set() for m in mods}
    for m, f in mods.items():
        for node in ast.walk(ast.parse(f.read_text(), str(f))):
            targets: list[str] = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                targets = [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Call) and _dynamic_import(node.func) and node.args:
                arg = node.args[0]
                if isinstance(arg, ast.Constant) and isinstance(arg.value, str):
                    targets = [arg.value]
            for t in targets:
                if t.split(".")[0] == "amigo_gym" and (r := resolve(t)) and r != m:
                    out[m].add(r)
    return out


def _dynamic_import(func: ast.expr) -> bool:
    name = func.attr if isinstance(func, ast.Attribute) else func.id if isinstance(func, ast.Name) else ""
    return name in ("import_module", "__import__")


def within(module: str, package: str) -> bool:
    """``module`` is ``package`` or inside it."""
    return module == package or module.startswith(package + ".")


def core_imports_of_tools(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """Imports from a module of the environment core to one of the tools layer (:data:`TOOLS`): there must be none."""
    return sorted((a, b) for a, bs in graph.items() for b in bs if not within(a, TOOLS) and within(b, TOOLS))


def imports_of_the_cli(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """Imports of the CLI (:data:`CLI`) from outside it: there must be none."""
    return sorted((a, b) for a, bs in graph.items() for b in bs if not within(a, CLI) and within(b, CLI))


def layer_of(module: str) -> int:
    """Index in :data:`LAYERS` of the longest prefix that names ``module`` or a package holding it."""
    best, best_len = -1, -1
    for i, (_, _, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            if within(module, p) and len(p) > best_len:
                best, best_len = i, len(p)
    return best


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    out: list[list[str]] = []
    sys.setrecursionlimit(10000)

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return out


def upward(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """Imports from a module to one of a higher layer (or of no layer)."""
    return sorted((a, b) for a, bs in graph.items() for b in bs if layer_of(b) > layer_of(a) or layer_of(a) < 0)


def root_modules(package: Path = PACKAGE) -> list[str]:
    return sorted(f.name for f in package.glob("*.py"))


def lines(files: list[Path]) -> int:
    return sum(len(f.read_text().splitlines()) for f in files)


def _plot(path: Path, mods: dict[str, Path], graph: dict[str, set[str]]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import FancyArrowPatch, FancyBboxPatch

    by_layer: dict[int, list[str]] = defaultdict(list)
    for m in mods:
        by_layer[layer_of(m)].append(m)
    fig, ax = plt.subplots(figsize=(11, 0.78 * len(LAYERS) + 0.6))
    ys = {i: i for i in range(len(LAYERS))}
    arrows: dict[tuple[int, int], int] = defaultdict(int)
    for a, bs in graph.items():
        for b in bs:
            if layer_of(a) != layer_of(b):
                arrows[(layer_of(a), layer_of(b))] += 1
    for i, (name, what, _) in enumerate(LAYERS):
        files = [mods[m] for m in by_layer[i]]
        ax.add_patch(
            FancyBboxPatch((0.0, ys[i] - 0.32), 6.2, 0.64, boxstyle="round,pad=0.02", fc="#e8eef7", ec="#35608f")
        )
        ax.text(0.12, ys[i] + 0.1, f"{name}", fontsize=11, weight="bold", va="center")
        ax.text(1.25, ys[i] + 0.1, what, fontsize=8.5, va="center")
        shown = sorted(
            {".".join(m.split(".")[1:3] if within(m, TOOLS) else m.split(".")[1:2]) or "__init__" for m in by_layer[i]}
        )
        ax.text(
            1.25,
            ys[i] - 0.17,
            f"{', '.join(shown)}   ({len(files)} modules, {lines(files):,} lines)",
            fontsize=7.5,
            va="center",
            color="#444",
        )
    for a, b in sorted(arrows):  # one arrow per pair of layers, right of the boxes
        x = 6.35 + 0.09 * (a % 6) + 0.03 * (b % 3)
        ax.add_patch(
            FancyArrowPatch(
                (x, ys[a] - 0.3),
                (x, ys[b] + 0.3),
                arrowstyle="-|>",
                mutation_scale=8,
                color="#c0392b" if b > a else "#7f8c8d",
                lw=0.6,
                alpha=0.8,
            )
        )
    ax.set_xlim(-0.1, 7.0)
    ax.set_ylim(-0.6, len(LAYERS) - 0.4)
    ax.axis("off")
    total = lines(list(mods.values()))
    ax.set_title(
        f"amigo_gym: {len(mods)} modules, {total:,} lines in {len(LAYERS)} layers; every import points down "
        "(grey arrows: layer to layer)",
        fontsize=10,
    )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plot", type=Path, help="write the layer picture here [png]")
    args = ap.parse_args(argv)
    mods = modules()
    graph = imports(mods)
    for i, (name, what, _) in enumerate(LAYERS):
        ms = sorted(m for m in mods if layer_of(m) == i)
        print(f"{i:2d} {name:<9} {lines([mods[m] for m in ms]):6d} lines  {len(ms):3d} modules  {what}")
    print(f"package: {len(mods)} modules, {lines(list(mods.values()))} lines; root modules: {root_modules()}")
    bad = upward(graph)
    loops = circles(graph)
    core = core_imports_of_tools(graph)
    print(f"upward imports: {len(bad)} {bad}\ncircles: {len(loops)} {loops}\ncore -> tools: {len(core)} {core}")
    if args.plot:
        _plot(args.plot, mods, graph)
        print(f"wrote {args.plot}")
    return 1 if bad or loops or core else 0


if __name__ == "__main__":
    raise SystemExit(main())
