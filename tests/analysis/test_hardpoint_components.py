"""One global coordinate of a hardpoint is an address everywhere (``hardpoint:TR.i[z]``,
``hardpoint:UCA.front[z]``): ``--set`` equals setting the whole point with the other two
coordinates where they are, ``--free`` frees the design columns a change of it writes; the
result is checked against the independent double-wishbone solver of ``dw_oracle``."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from analysis_helpers import EXAMPLES
from dw_oracle import HMMWV, solve
from typer.testing import CliRunner

import kinprop as kp
from kinprop import SingularityWarning
from kinprop.analysis.metrics import suspension_metrics
from kinprop.cli import app
from kinprop.engine import compile as compile_engine
from kinprop.errors import AddressError
from kinprop.propagation.hardpoints import current_point, free_addresses, resolve_changes

FILE = EXAMPLES / "double_wishbone_hardpoints.yaml"
METRICS = ("camber", "toe", "kpi", "caster")


def _propagate(model, changes, free=("q",)):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        p = kp.propagate(model, changes, free, tol=1e-10)
    assert p.converged, p.result.message
    return p.after


def _same_design(a, b):
    for k, v in a.design.items():
        np.testing.assert_array_equal(np.asarray(v), np.asarray(b.design[k]), err_msg=k)
    for body in a.mechanism.bodies:
        pa, pb = dict(body.points), dict(b.mechanism.body(body.name).points)
        for k in pa:
            np.testing.assert_array_equal(pa[k], pb[k], err_msg=f"{body.name}.{k}")


@pytest.mark.parametrize(
    ("component", "whole", "key", "c", "value"),
    [
        ("hardpoint:TR.i[z]", "hardpoint:TR.i", "TR_I", 2, 60.0),
        ("hardpoint:UBJ[y]", "hardpoint:UBJ", "UBJ", 1, 721.0),
        ("hardpoint:UCA.front[z]", "hardpoint:UCA.front", "UCA_F", 2, 254.62232),
    ],
)
def test_a_component_equals_the_whole_point(component, whole, key, c, value):
    """The API: one coordinate set is the whole point set with the other two kept; over 4 deg
    of lower arm the metrics equal the independent solver's with that hardpoint moved."""
    model = kp.load_model(FILE)
    eng = compile_engine(model)
    p = current_point(eng, eng.reference, whole)  # the file's numbers (HMMWV's differ by rounding)
    np.testing.assert_allclose(p, HMMWV[key], atol=1e-12)
    p[c] = value
    one, full = _propagate(model, {component: value}), _propagate(model, {whole: p})
    _same_design(one, full)
    at_4 = suspension_metrics(_propagate(one, {"LCA.q": 4.0}), "upright")
    truth = solve({**HMMWV, key: p}, 4.0)
    for name in METRICS:
        assert at_4[name] == pytest.approx(truth[name], abs=1e-7), name


def test_two_components_of_one_point_merge():
    model = kp.load_model(FILE)
    eng = compile_engine(model)
    p = current_point(eng, eng.reference, "hardpoint:TR.i") + [3.0, 0.0, -2.0]
    parts = resolve_changes(eng, eng.reference, {"hardpoint:TR.i[x]": p[0], "hardpoint:TR.i[z]": p[2]})
    whole = resolve_changes(eng, eng.reference, {"hardpoint:TR.i": p})
    assert parts.keys() == whole.keys()
    for k in whole:
        np.testing.assert_array_equal(parts[k], whole[k])


def test_free_a_component_frees_the_columns_it_writes():
    model = kp.load_model(FILE)
    eng = compile_engine(model)
    assert free_addresses(eng, ["hardpoint:TR.i[z]"]) == ("TR.s_i[2]", "TR.length")
    mech = compile_engine(kp.load_model(EXAMPLES / "double_wishbone.yaml"))  # edits: mechanism, turned frames
    assert free_addresses(mech, ["hardpoint:TR.i[z]"]) == ("TR.s_i[2]",)
    with pytest.raises(AddressError, match=r"turned from the global axes.*UBJ.s_i\[0\]"):
        free_addresses(mech, ["hardpoint:UBJ[x]"])


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"hardpoint:TR.i[w]": 1.0}, r"expected a component \[x\], \[y\] or \[z\]"),
        ({"hardpoint:TR.i[z]": [1.0, 2.0]}, "expected one finite global coordinate"),
        ({"hardpoint:TR.i[z]": 1.0, "hardpoint:TR.i": [0.0, 0.0, 0.0]}, "already given"),
        ({"axis:UCA[z]": 1.0}, "an axis is a direction"),
    ],
)
def test_bad_components_are_refused(changes, message):
    eng = compile_engine(kp.load_model(FILE))
    with pytest.raises(AddressError, match=message):
        resolve_changes(eng, eng.reference, changes)


def _cli(*args):
    return CliRunner().invoke(app, [str(a) for a in args])


def test_cli_set_and_free_take_components():
    """``propagate --set hardpoint:TR.i[z]=60`` prints what ``--set hardpoint:TR.i=x,y,60``
    does (the file's TR.i is -250.317, 448.437, 54.229); ``--free hardpoint:TR.i[z]`` finds the
    same zero-bump-steer height as ``--free TR.s_i[2] --free TR.length``; a bad component exits
    2 naming it."""
    one = _cli("propagate", FILE, "--set", "hardpoint:TR.i[z]=60", "--json")
    full = _cli("propagate", FILE, "--set", "hardpoint:TR.i=-250.317,448.437,60", "--json")
    assert one.exit_code == 0 and full.exit_code == 0, one.output + full.output
    assert json.loads(one.stdout)["design"] == json.loads(full.stdout)["design"]
    targets = ["--target", "slope:toe@travel=-50..50mm=0deg/m", "--target", "toe@travel=0=0", "--json"]
    a = _cli("propagate", FILE, *targets, "--free", "hardpoint:TR.i[z]")
    b = _cli("propagate", FILE, *targets, "--free", "TR.s_i[2]", "--free", "TR.length")
    assert a.exit_code == 0 and b.exit_code == 0, a.output + b.output
    za, zb = (json.loads(r.stdout)["design"]["TR.s_i"][2] for r in (a, b))
    assert za == pytest.approx(zb, abs=1e-9) and za == pytest.approx(59.7907, abs=1e-4)
    bad = _cli("propagate", FILE, "--set", "hardpoint:TR.i[q]=60")
    assert bad.exit_code == 2 and "hardpoint:TR.i[q]" in bad.output


def test_a_free_component_of_a_ball_joint_moves_that_coordinate_alone(tmp_path):
    """``--free hardpoint:UBJ[z]`` in a target is one unknown, the ball joint's height: both
    bodies' s' move by the same global step, so UBJ keeps its x and y (freed one by one, the
    upper arm turned and UBJ moved 9 mm in x too). The target met is the independent solver's
    camber with UBJ at the returned height; the design position keeps its camber."""
    out = tmp_path / "ubj.yaml"
    r = _cli("propagate", FILE, "--target", "camber@LCA.q=4=-1.0", "--free", "hardpoint:UBJ[z]", "-o", out, "--json")
    assert r.exit_code == 0, r.output
    after = kp.load_model(out)
    eng = compile_engine(after)
    p = current_point(eng, eng.reference, "hardpoint:UBJ")
    np.testing.assert_allclose(p[:2], HMMWV["UBJ"][:2], atol=1e-9)
    assert abs(p[2] - HMMWV["UBJ"][2]) > 1.0  # it did move
    truth = solve({**HMMWV, "UBJ": p}, 4.0)
    assert truth["camber"] == pytest.approx(-1.0, abs=1e-7)
    before = suspension_metrics(kp.load_model(FILE), "upright")
    assert suspension_metrics(after, "upright")["camber"] == pytest.approx(before["camber"], abs=1e-9)
