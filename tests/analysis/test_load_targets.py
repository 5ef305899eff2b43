"""Load targets (``--target reaction:UBJ.f@CASE<=8kN``): values are kp.statics' at the solved
design, the rows' rates are exact (against central differences of re-solved models), a bound
that holds does not move the design, a violated one is driven onto its limit, and two bounds
that cannot both hold are reported in conflict."""

from __future__ import annotations

import numpy as np
import pytest

import kinprop as kp
from kinprop.analysis.targets import _config_rates, propagate_targets
from kinprop.errors import AddressError


def test_rates_are_exact(double_wishbone: kp.Model) -> None:
    """The configuration's rates along ``e_p + dq/dp`` (the lower arm held, every other
    coordinate following) equal central differences of re-solved models."""
    m = double_wishbone
    eng = kp.compile(m)
    names = ["reaction:UBJ.f@braking_1g", "force:TR@cornering_1g", "point:upright.wheel_centre[z]"]
    st = eng.state_of(m)
    col = eng.columns(["UBJ.s_j[2]"])
    inner = np.setdiff1d(eng.columns(["q"]), eng.columns(["LCA.q"]))
    _, J = eng.evaluate(st)
    X = np.zeros((1, eng.n_columns))
    X[0, col] = 1.0
    X[0, inner] = -np.linalg.lstsq(J[:, inner], J[:, col], rcond=None)[0][:, 0]
    exact = _config_rates(m, eng, names)(st, X)[:, 0]
    h = 1e-3
    vals = []
    for sgn in (1.0, -1.0):
        at = kp.propagate(m, {"UBJ.s_j[2]": m.design["UBJ.s_j"][2] + sgn * h}, free=["q"], tol=1e-13).after
        vals.append([kp.statics(at, n.split("@")[1], reference=m).value(n.split("@")[0]) for n in names[:2]]
                    + [kp.evaluate_outputs(at, names[2:])[names[2]]])  # fmt: skip
    fd = (np.array(vals[0]) - np.array(vals[1])) / (2 * h)
    assert np.allclose(exact, fd, rtol=1e-6, atol=1e-9 * np.abs(fd).max())


def test_bounds_over_the_load_cases(double_wishbone: kp.Model) -> None:
    m = double_wishbone
    before = {c: kp.statics(m, c).value("reaction:UBJ.f") for c in m.loads.cases}
    loose = propagate_targets(m, ["reaction:UBJ.f@*<=20kN"], free=["hardpoint:UBJ"])
    assert loose.met and all(np.allclose(d, 0.0) for d in loose.design_change.values())
    assert [r["target"] for r in loose.table()] == [f"reaction:UBJ.f@{c}<=20kN" for c in m.loads.cases]
    tight = propagate_targets(m, ["reaction:UBJ.f@*<=8kN"], free=["hardpoint:UBJ"])
    assert tight.met and min(before.values()) > 8000.0
    after = tight.after_model(0)
    got = {c: kp.statics(after, c, reference=m).value("reaction:UBJ.f") for c in m.loads.cases}
    assert max(got.values()) == pytest.approx(8000.0, rel=1e-9)  # the worst case on its limit
    assert all(v <= 8000.0 * (1 + 1e-9) for v in got.values())
    both = propagate_targets(
        m, ["reaction:UBJ.f@braking_1g<=1kN", "reaction:UBJ.f@braking_1g>=2kN"], free=["hardpoint:UBJ"]
    )
    assert not both.met and both.converged
    assert {n for g in both.result.conflicts for n, _ in g} == {s.text for s in both.specs}
    assert [r["miss"] for r in both.table()] == pytest.approx([500.0, -500.0], rel=1e-6)
    one = propagate_targets(m, ["reaction:UBJ.f@*<=8kN"], free=["UBJ.s_j[0]"])  # too little freedom
    assert one.converged and not one.met and one.result.conflicts
    worst = max(kp.statics(one.after_model(0), c, reference=m).value("reaction:UBJ.f") for c in m.loads.cases)
    assert 8000.0 < worst < before["braking_1g"]
    with pytest.raises(AddressError, match="unknown load case 'nope'"):
        propagate_targets(m, ["force:TR@nope=1"], free=["hardpoint:UBJ"])
