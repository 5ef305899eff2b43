"""The pipeline is the layout: no module imports a higher layer, no import cycles between
modules or between top-level folders, and no function-local imports of kinprop's own modules
outside ``cli/`` (docs/architecture.md). Imports under ``if TYPE_CHECKING:`` count: a cycle that
only type checkers see is still a cycle of the design."""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx

SRC = Path(__file__).resolve().parents[1] / "src" / "kinprop"

#: layer of each top-level module or package, in pipeline order (a module may import its own
#: layer and the ones below)
LAYERS = {
    "errors": 0, "jit": 0, "spatial": 0, "resources": 0, "__main__": 14,
    "constraints": 1, "joints": 2, "model": 3, "topology": 4, "kinematics": 5, "solver": 6, "engine": 7,
    "propagation": 8, "analysis": 9, "builders": 9,
    "io": 10, "imports": 10, "reference": 11, "plot": 11, "serve": 12, "cli": 13, "__init__": 14,
}  # fmt: skip


def module_name(path: Path) -> str:
    rel = path.relative_to(SRC.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def layer(module: str) -> int:
    parts = module.split(".")
    return LAYERS["__init__"] if len(parts) == 1 else LAYERS[parts[1]]


def _type_checking_blocks(tree: ast.Module) -> set[int]:
    """Line numbers of the module-level ``if TYPE_CHECKING:`` blocks' statements."""
    lines: set[int] = set()
    for node in tree.body:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for sub in node.body:
                lines.update(range(sub.lineno, (sub.end_lineno or sub.lineno) + 1))
    return lines


def imports(path: Path) -> tuple[list[str], list[tuple[int, str]]]:
    """(module-level kinprop imports, ``if TYPE_CHECKING:`` ones included; [(line, module)] of
    function-local ones)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    typing_only = _type_checking_blocks(tree)
    top, local = [], []
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("kinprop"):
            names = [node.module]
        elif isinstance(node, ast.Import):
            names = [a.name for a in node.names if a.name.startswith("kinprop")]
        else:
            continue
        if not names:
            continue
        if node.col_offset == 0 or node.lineno in typing_only:
            top += names
        else:
            local += [(node.lineno, n) for n in names]
    return top, local


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in SRC.rglob("*.py")}


def test_every_top_level_module_has_a_layer():
    tops = {m.split(".")[1] for m in modules() if "." in m}
    assert tops <= set(LAYERS), sorted(tops - set(LAYERS))


def test_no_upward_imports_and_no_local_imports_outside_the_cli():
    upward, local_imports = [], []
    for name, path in modules().items():
        top, local = imports(path)
        for target in top:
            if layer(target) > layer(name):
                upward.append(f"{name} imports {target}")
        if not name.startswith("kinprop.cli") and layer(name) < LAYERS["__init__"]:
            local_imports += [f"{name}:{line} imports {t}" for line, t in local]
    assert not upward, "\n".join(upward)
    assert not local_imports, "\n".join(local_imports)


def test_no_import_cycles():
    g = nx.DiGraph()
    mods = modules()
    for name, path in mods.items():
        for target in imports(path)[0]:
            # `from kinprop.x import y` may name a submodule y or an attribute of x
            g.add_edge(name, target if target in mods else target.rsplit(".", 1)[0])
    # a package's __init__ re-exporting its own submodules is not a cycle
    g.remove_edges_from([(a, b) for a, b in list(g.edges) if b.startswith(a + ".") or a == b])
    cycles = list(nx.simple_cycles(g))
    assert not cycles, cycles[:5]


def folder(module: str) -> str:
    """The top-level folder (or module) of ``kinprop.x.y``: ``x``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


#: folder pairs that import each other, with the reason (module-level there is no cycle): the
#: one left is that ``io.files.load_model`` reads foreign files through ``imports/``, whose
#: importers build models through ``io.hardpoints`` (splitting it moves ``load_model``)
TWO_WAY = {frozenset({"io", "imports"})}


def test_top_level_folders_import_each_other_one_way():
    """Between two folders imports go one way only, also between folders of one layer
    (``serve/`` uses the library, never ``cli/``; ``io/`` and ``imports/``; ``plot/`` and
    ``reference/``); every import of a module, function-local ones included."""
    g = nx.DiGraph()
    for name, path in modules().items():
        top, local = imports(path)
        for target in top + [t for _, t in local]:
            a, b = folder(name), folder(target)
            if a != b and "kinprop" not in (a, b) and a != "__main__":
                g.add_edge(a, b, example=f"{name} imports {target}")
    pairs = [
        f"{a} <-> {b}: {g.edges[a, b]['example']}; {g.edges[b, a]['example']}"
        for a, b in g.edges
        if a < b and g.has_edge(b, a) and frozenset({a, b}) not in TWO_WAY
    ]
    assert not pairs, "\n".join(pairs)
    g.remove_edges_from([(a, b) for a, b in list(g.edges) if frozenset({a, b}) in TWO_WAY])
    cycles = list(nx.simple_cycles(g))
    assert not cycles, cycles[:5]
    assert not g.has_edge("serve", "cli"), g.edges["serve", "cli"]["example"]
