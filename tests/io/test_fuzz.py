"""Property test: corrupted model files load as a valid model or fail with a clean ModelError.

Hypothesis corrupts the shipped examples (both styles) at random — deletes keys, replaces
values with wrong types, NaN, text, huge lists, renames bodies, changes joint types,
duplicates entries, and mangles the text itself — and checks that kinprop either builds a
model (which then converts to hardpoints and back) or raises :class:`ModelError`: never any
other exception. Through the CLI the same means exit code 0 or 2 with clean ``error:`` lines.
"""

from __future__ import annotations

import contextlib
import copy
import math
import os
from pathlib import Path
from typing import Any

import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from kinprop.cli import app
from kinprop.errors import ModelError
from kinprop.io import load_model, model_from_data
from kinprop.io.hardpoints import model_to_hardpoints
from kinprop.joints import ALIASES, REGISTRY
from kinprop.model import Model

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
FILES = sorted(EXAMPLES.glob("*.yaml"))
TEXTS = {p.name: p.read_text() for p in FILES}
DATA = {name: yaml.safe_load(text) for name, text in TEXTS.items()}
#: KINPROP_FUZZ_EXAMPLES=5000 for a longer local hunt
N = int(os.environ.get("KINPROP_FUZZ_EXAMPLES", "150"))
#: fixed examples in CI; random ones in a local hunt
FIXED = "KINPROP_FUZZ_EXAMPLES" not in os.environ
runner = CliRunner()

BAD_VALUES = st.one_of(
    st.sampled_from(
        [None, math.nan, math.inf, -math.inf, 1e308, -1e308, 0, -1, 0.0, True, False, "", "text", "1.5", [], {}]
        + [[1, 2], [1, 2, 3, 4], [math.nan] * 3, [[1, 0, 0]] * 3, [[0] * 3] * 3, ["a", "b", "c"], [None] * 3]
        + [[1e308] * 3, [1e-320] * 3, [[1, 0, 0], [0, 1, 0]], {"a": 1}, [[1, 2, 3]] * 4, [0, 0, 0], [0.0, 0.0, 1e-13]]
        + ["fixed", "revolute", "S-T", "__world__", "ground", "chassis", "J12.s_j", "hardpoints", "frames", "mm"]
    ),
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.text(max_size=8),
    st.lists(st.floats(min_value=-1e6, max_value=1e6), min_size=0, max_size=6),
    st.lists(st.floats(), min_size=1000, max_size=1000),
    st.lists(st.lists(st.floats(min_value=-2, max_value=2), min_size=3, max_size=3), min_size=3, max_size=3),
)
JOINT_TYPES = sorted(REGISTRY) + sorted(ALIASES) + ["hinge", "", "Revolute"]


def paths(tree: Any, prefix: tuple = ()) -> list[tuple]:
    """Every path into a nested dict/list structure (the root excluded)."""
    out = []
    items = tree.items() if isinstance(tree, dict) else enumerate(tree) if isinstance(tree, list) else ()
    for k, v in items:
        out.append((*prefix, k))
        if len(out) < 400:
            out += paths(v, (*prefix, k))
    return out


def parent(tree: Any, path: tuple) -> Any:
    for k in path[:-1]:
        tree = tree[k]
    return tree


@st.composite
def corrupted(draw: st.DrawFn) -> tuple[str, Any]:
    """(file name, corrupted data) or (file name, corrupted text)."""
    name = draw(st.sampled_from(sorted(DATA)))
    if draw(st.integers(0, 4)) == 0:
        lines = TEXTS[name].splitlines(keepends=True)
        for _ in range(draw(st.integers(1, 3))):
            k = draw(st.integers(0, max(len(lines) - 1, 0)))
            op = draw(st.sampled_from(["delete", "duplicate", "truncate", "char", "swap"]))
            if not lines:
                break
            if op == "delete":
                del lines[k]
            elif op == "duplicate":
                lines.insert(k, lines[k])
            elif op == "truncate":
                lines[k] = lines[k][: draw(st.integers(0, len(lines[k])))]
            elif op == "char":
                pos = draw(st.integers(0, len(lines[k])))
                lines[k] = lines[k][:pos] + draw(st.sampled_from(list("[]{}:,-&*!'\"#\t\\ 0x."))) + lines[k][pos:]
            else:
                j = draw(st.integers(0, len(lines) - 1))
                lines[k], lines[j] = lines[j], lines[k]
        return name, "".join(lines)
    data = copy.deepcopy(DATA[name])
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["delete", "replace", "replace", "rename_body", "joint_type", "duplicate", "fix"]))
        if op in ("delete", "replace"):
            ps = paths(data)
            if not ps:
                break
            path = draw(st.sampled_from(ps))
            holder = parent(data, path)
            if op == "delete":
                del holder[path[-1]]
            else:
                holder[path[-1]] = draw(BAD_VALUES)
        elif op == "rename_body" and isinstance(data.get("bodies"), dict) and data["bodies"]:
            old = draw(st.sampled_from(sorted(map(str, data["bodies"]))))
            new = draw(st.sampled_from(["ground", "chassis", "wheel", "x", "__world__", "", "rod", old + "2"]))
            data["bodies"] = {(new if str(k) == old else k): v for k, v in data["bodies"].items()}
        elif op == "joint_type" and isinstance(data.get("joints"), dict) and data["joints"]:
            j = draw(st.sampled_from(sorted(map(str, data["joints"]))))
            if isinstance(data["joints"].get(j), dict):
                data["joints"][j]["type"] = draw(st.sampled_from(JOINT_TYPES))
        elif op == "duplicate":
            section = draw(st.sampled_from(["bodies", "joints"]))
            if isinstance(data.get(section), dict) and data[section]:
                k = draw(st.sampled_from(sorted(map(str, data[section]))))
                if k in data[section]:
                    data[section][k + "_copy"] = copy.deepcopy(data[section][k])
        elif op == "fix" and isinstance(data.get("bodies"), dict) and data["bodies"]:
            k = draw(st.sampled_from(sorted(map(str, data["bodies"]))))
            if isinstance(data["bodies"].get(k), dict):
                data["bodies"][k]["fixed"] = draw(st.booleans())
    return name, data


def check_model(model: Model) -> None:
    """A model that loads also converts to hardpoints and back (or is cleanly refused)."""
    assert isinstance(model, Model)
    with contextlib.suppress(ModelError):
        model_from_data(model_to_hardpoints(model))


@settings(max_examples=N, deadline=None, derandomize=FIXED, suppress_health_check=list(HealthCheck))
@given(case=corrupted())
def test_corrupted_files_load_or_raise_model_error(case, tmp_path_factory):
    name, data = case
    if isinstance(data, str):
        path = tmp_path_factory.mktemp("fuzz") / name
        path.write_text(data)
        load = lambda: load_model(path)  # noqa: E731
    else:
        load = lambda: model_from_data(data, name)  # noqa: E731
    try:
        model = load()
    except ModelError as exc:
        assert exc.problems and all(p.location and p.message for p in exc.problems)
        return
    check_model(model)


@settings(max_examples=max(N // 5, 10), deadline=None, derandomize=FIXED, suppress_health_check=list(HealthCheck))
@given(case=corrupted())
def test_corrupted_files_through_the_cli(case, tmp_path_factory):
    name, data = case
    path = tmp_path_factory.mktemp("fuzzcli") / name
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data, sort_keys=False))
    r = runner.invoke(app, ["convert", str(path), "--to", "hardpoints", "-o", str(path.with_suffix(".hp.yaml"))])
    assert r.exit_code in (0, 2), r.output
    assert r.exception is None or isinstance(r.exception, SystemExit), repr(r.exception)
    if r.exit_code == 2:
        lines = [line for line in r.stderr.splitlines() if line.strip()]
        assert lines and all(line.startswith("error: ") for line in lines), r.stderr
