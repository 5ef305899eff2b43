"""Weighted free sets and locks, end to end: API, CLI and sensitivities use the same weights."""

from __future__ import annotations

import json

import numpy as np
import pytest
from analysis_helpers import resolve_fd

from kinprop import AddressError, propagate
from kinprop.analysis.outputs import output_function
from kinprop.analysis.sensitivity import design_sensitivity, output_sensitivity

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")

PREFER_TIE_ROD = {"TD.s_i": 100.0, "TD.s_j": 100.0, "RS.s_i": 0.01, "RS.s_j": 0.01}
PREFER_ARM = {"TD.s_i": 0.01, "TD.s_j": 0.01, "RS.s_i": 100.0, "RS.s_j": 100.0}


def moved(before, after, keys):
    return float(np.linalg.norm(np.concatenate([np.ravel(after.design[k] - before.design[k]) for k in keys])))


def top_mount_change(model, dx=0.005):
    s = np.array(model.design["ST.s_i"])
    s[0] += dx
    return {"ST.s_i": s}


def test_prefer_moving_the_tie_rod_over_the_control_arm(mcpherson):
    change = top_mount_change(mcpherson)
    ratios = {}
    for label, w in (("plain", None), ("tie rod", PREFER_TIE_ROD), ("arm", PREFER_ARM)):
        prop = propagate(mcpherson, change, ("q", "s"), weights=w)
        assert prop.converged, prop.result.message
        td = moved(mcpherson, prop.after, ["TD.s_i", "TD.s_j"])
        rs = moved(mcpherson, prop.after, ["RS.s_i", "RS.s_j"])
        ratios[label] = td / rs
    # unweighted the arm takes more; weighted, the correction goes mostly to the preferred side
    assert ratios["tie rod"] > 5.0 > 1.0 > ratios["plain"] > 0.2 > 0.1 > ratios["arm"]


def test_weights_only_matter_between_competing_variables(mcpherson):
    # with s' alone free each cut joint is corrected by its own s' only: weights cannot trade
    change = top_mount_change(mcpherson)
    a = propagate(mcpherson, change, ("s",))
    b = propagate(mcpherson, change, ("s",), weights=PREFER_TIE_ROD)
    for k in ("RS.s_i", "RS.s_j", "TD.s_i", "TD.s_j"):
        np.testing.assert_allclose(a.after.design[k], b.after.design[k], atol=1e-12)


def test_locks_by_free_set(mcpherson):
    change = top_mount_change(mcpherson)
    prop = propagate(mcpherson, change, ("q", "RS.s_i", "TD.s_j"))
    assert prop.converged
    changed = set(prop.changed_variables())
    assert {"RS.s_i", "TD.s_j", "ST.s_i"} <= changed
    assert not changed & {"RS.s_j", "TD.s_i", "RS.length", "TD.length"}  # locked: not in the free set
    for k in ("RS.s_j", "TD.s_i"):
        assert np.array_equal(prop.after.design[k], mcpherson.design[k])


def test_sensitivity_uses_the_same_weights(mcpherson):
    free = ("q", "s")
    of = ["TD.s_i", "RS.s_j", "ST.q", "camber"]
    f, _ = output_function(mcpherson, of)
    # the re-solve FD oracle differences output_function, which is in solver units
    plain = output_sensitivity(mcpherson, of, ["ST.s_i[0]"], free, units="solver")
    weighted = output_sensitivity(mcpherson, of, ["ST.s_i[0]"], free, PREFER_TIE_ROD, units="solver")
    assert not np.allclose(plain.to_numpy(), weighted.to_numpy(), atol=1e-3)
    for w, D in ((None, plain), (PREFER_TIE_ROD, weighted)):
        fd = resolve_fd(mcpherson, f, "ST.s_i[0]", 1e-6, free=free, weights=w)
        np.testing.assert_allclose(D["ST.s_i[0]"].to_numpy(), fd, rtol=1e-6, atol=1e-8)
    S = design_sensitivity(mcpherson, ["ST.s_i[0]"], free, PREFER_TIE_ROD).frame()
    td = np.linalg.norm(S.loc[[r for r in S.index if r.startswith("TD.s")]].to_numpy())
    rs = np.linalg.norm(S.loc[[r for r in S.index if r.startswith("RS.s")]].to_numpy())
    assert td > 5 * rs


def test_bad_weights_rejected(mcpherson):
    with pytest.raises(AddressError, match="positive"):
        design_sensitivity(mcpherson, ["ST.s_i"], ("q", "s"), {"TD.s_i": 0.0})
    with pytest.raises(AddressError):
        design_sensitivity(mcpherson, ["ST.s_i"], ("q", "s"), {"XX.s_i": 2.0})


def test_cli_weights_end_to_end(mcpherson, tmp_path):
    from typer.testing import CliRunner

    from kinprop import dump_model, load_model
    from kinprop.cli import app

    path = tmp_path / "mcpherson_solved.yaml"
    dump_model(mcpherson, path)
    s = top_mount_change(mcpherson)["ST.s_i"]
    weights = [a for k, v in PREFER_TIE_ROD.items() for a in ("--weight", f"{k}={v}")]
    value = ",".join(repr(float(x)) for x in s)
    args = ["propagate", str(path), "--set", f"ST.s_i={value}", "--free", "q", "--free", "s"]
    r = CliRunner().invoke(app, [*args, *weights, "-o", str(tmp_path / "out.yaml"), "--json"])
    assert r.exit_code == 0, r.output
    api = propagate(mcpherson, {"ST.s_i": s}, ("q", "s"), weights=PREFER_TIE_ROD)
    cli_after = load_model(tmp_path / "out.yaml")
    for k in ("TD.s_i", "TD.s_j", "RS.s_i", "RS.s_j"):
        np.testing.assert_allclose(cli_after.design[k], api.after.design[k], atol=1e-9)
    json.loads(r.stdout)
    r = CliRunner().invoke(
        app, ["sensitivity", str(path), "--wrt", "ST.s_i[0]", "--free", "q", "--free", "s", *weights, "--json"]
    )
    assert r.exit_code == 0, r.output
    obj = json.loads(r.stdout)
    S = design_sensitivity(mcpherson, ["ST.s_i[0]"], ("q", "s"), PREFER_TIE_ROD).frame()
    assert obj["of"] == list(S.index)
    np.testing.assert_allclose(np.array(obj["matrix"])[:, 0], S.iloc[:, 0].to_numpy(), atol=1e-8)
