"""A propagation's notebook summary (issue 11, item 7): compact text and an HTML table.

``kinprop.io.results.summary_text`` / ``summary_html`` are what ``Propagation.__repr__`` and
``_repr_html_`` return (the engine owner wires them in)."""

from __future__ import annotations

import math

import pytest

import kinprop as kp
from kinprop.io.results import summary_html, summary_text


@pytest.fixture(scope="module")
def prop(examples):
    model = kp.load_model(examples / "slider_crank.yaml")
    return kp.propagate(model, {"J12.s_j": [-2.8, 0.2, 0.1]}, tol=1e-3)


def test_summary_text_is_compact(prop) -> None:
    text = summary_text(prop)
    lines = text.splitlines()
    assert len(text) < 800 and len(lines) <= 10
    assert lines[0].startswith("<Propagation of 'spatial slider-crank") and "converged in 2 iterations" in lines[0]
    assert "||Phi|| = 1.27e-05" in lines[0]  # the paper's stopping rule, 2 iterations (Table 4)
    assert lines[1].strip().startswith("set J12.s_j: [-2.828, 0, 0] -> [-2.8, 0.2, 0.1]")
    moved = [x for x in lines[2:] if "moved" in x]
    assert {x.split()[1].rstrip(":") for x in moved} == set(prop.changed_variables()) - {"J12.s_j"}
    j01 = next(x for x in moved if "J01.q" in x)
    after = math.degrees(float(prop.after.coordinates["J01"][0]))
    assert j01.endswith(f"-> {after:.6g} deg")


def test_summary_html_is_a_table(prop) -> None:
    html = summary_html(prop)
    assert html.count("<tr>") == 1 + len(set(prop.changed_variables()) | {"J12.s_j"})
    assert "<th>max |change|</th>" in html and "J12.s_j" in html and "<script" not in html
