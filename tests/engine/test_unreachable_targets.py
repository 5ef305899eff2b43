"""Targets one free variable cannot reach (issue 24: the target solver's outer step): the
iteration ends at the least-squares best within reach, ``compromise``, with the design a
bounded distance away, where it ran off to 1e36 mm (a motion ratio by an element point) or
bounced for 50 iterations (camber by one ball-joint coordinate). Truth: the achieved value is a
local extremum of the output over the free variable, checked by re-solved models on both sides;
and the same steps in a model written in mm and in m."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from kinprop import load_model, propagate
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.analysis.targets import propagate_targets
from kinprop.engine import compile as compile_engine
from kinprop.propagation.element_points import element_point

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
DW = EXAMPLES / "double_wishbone.yaml"


def _value(model, changes: dict, output: str) -> float:
    return evaluate_outputs(propagate(model, changes, ["q"], tol=1e-13).after, [output])[output]


def test_an_unreachable_motion_ratio_ends_at_the_largest_one_within_reach():
    """motion_ratio:spring=5 by the spring's lower end sideways: the ratio peaks at 0.5614 (the
    solver ran the point to 1.3e36 mm and called that a compromise; the CLI's exit and JSON:
    tests/cli/test_targets_cli.py)."""
    model = load_model(DW)
    tp = propagate_targets(model, ["motion_ratio:spring=5"], ["element:spring.point_j[y]"])
    assert tp.targets_status == "compromise", tp.result.message
    (dy,) = tp.design_change["element:spring.point_j[y]"]
    assert 10.0 < abs(dy) < 1000.0  # moved, and by less than the suspension's size (mm)
    best = tp.table()[0]["achieved"]
    eng = compile_engine(model)
    y = float(element_point(model, eng, eng.state_of(model), "element:spring.point_j[y]")[0]) + dy
    for h in (-1.0, 1.0):
        assert _value(model, {"element:spring.point_j[y]": y + h}, "motion_ratio:spring") < best
    assert _value(model, {"element:spring.point_j[y]": y}, "motion_ratio:spring") == pytest.approx(best, abs=1e-9)


def test_an_unreachable_camber_ends_at_the_most_negative_one_within_reach():
    model = load_model(DW)
    tp = propagate_targets(model, ["camber=-60"], ["UBJ.s_j[2]"])
    assert tp.targets_status == "compromise", tp.result.message
    dz = float(tp.design_change["UBJ.s_j"][2])
    assert 10.0 < abs(dz) < 1000.0
    best = tp.table()[0]["achieved"]
    assert -60.0 < best < -15.0
    s = np.asarray(tp.after.design["UBJ.s_j"], float)
    for h in (-0.5, 0.5):
        assert _value(tp.after, {"UBJ.s_j": s + [0.0, 0.0, h]}, "camber") > best
    assert not tp.result.conflicts or tp.result.conflicts[0][0][0] == "camber=-60"


def test_a_target_no_free_variable_changes_does_not_move_the_design():
    """Caster by the tie rod's inner point: no change, a compromise naming the target."""
    tp = propagate_targets(load_model(DW), ["caster=60"], ["TR.s_i[0]"])
    assert tp.targets_status == "compromise"
    assert float(np.abs(tp.design_change["TR.s_i"]).max()) == 0.0
    assert [n for n, _ in tp.result.conflicts[0]] == ["caster=60"]


@pytest.mark.parametrize(
    ("target", "free", "status"),
    [("J03.q=10m", ["J12.s_i[0]", "J12.s_j[0]", "axis:J32"], "compromise"),
     ("J03.q=1m", ["J12.s_i[0]", "axis:J01"], "met")],
)  # fmt: skip
def test_the_same_steps_in_millimetres_and_in_metres(target: str, free: list[str], status: str) -> None:
    """The slider-crank in m and in mm (a mechanism with mobility: the coordinates' response is
    the least change in SI units): the same design change, met or the same compromise at the
    limit of a design change (the mechanism's size, 3.86 m)."""
    m, mm = (propagate_targets(load_model(EXAMPLES / f), [target], free)
             for f in ("slider_crank.yaml", "slider_crank_mm.yaml"))  # fmt: skip
    assert m.targets_status == mm.targets_status == status, (m.result.message, mm.result.message)
    assert m.table()[0]["achieved"] * 1000.0 == pytest.approx(mm.table()[0]["achieved"], rel=1e-8)
    for key, d in m.design_change.items():
        k = 1.0 if key.endswith((".C_i", ".C_j")) else 1000.0
        np.testing.assert_allclose(mm.design_change[key], k * d, rtol=1e-7, atol=1e-7 * k)
    # the metre model's change: metres and radians, within the mechanism's size
    assert np.sqrt(sum(float(np.sum(d**2)) for d in m.design_change.values())) <= 3.8637 + 1e-6
