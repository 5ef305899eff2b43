"""Issue 10 item 7: the default solve paths keep the start's assembly branch, checked against
closed forms (external truth) on every classic example: four-bar crank-rocker and double
rocker (Freudenstein), spatial RSSR (input-output equation), Bennett (Baker), spherical
four-bar (spherical Freudenstein equation) and offset slider-crank (x(theta) with offset e).

Every check also measures how far the *other* root is, so a result on the wrong branch
fails by tens of degrees, never by a tolerance."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from linkages import (
    CRANK_ROCKER,
    DOUBLE_ROCKER,
    EXAMPLES,
    OFFSET_SLIDER,
    SPHERICAL,
    bennett_theta2,
    freudenstein,
    input_limit,
    load_solved,
    rssr_phi,
    set_crank,
    set_input,
    slider_x,
    spherical_axes,
    spherical_phi,
    wrap,
)

import kinprop as kp
from kinprop import SingularityWarning, load_model
from kinprop.analysis.sweep import Drive
from kinprop.builders import RSSR, rssr
from kinprop.engine import compile as compile_engine

TOL_DEG = 1e-8  # closed-form agreement [deg]; measured 1e-14 .. 5e-11 (the spherical file's matrices have 12 digits)


def _rssr_length(model: kp.Model) -> float:
    return float(np.atleast_1d(model.design["coupler.length"])[0])


def _rssr(t, length: float, branch: int = +1):
    return rssr_phi(t, RSSR["crank"], RSSR["pivot"], RSSR["rocker"], length, branch)


# --- the closed forms themselves ---------------------------------------------------------------
def test_spherical_closed_form_is_the_axis_angle():
    """The spherical Freudenstein equation (both roots) puts u2 and u3 at alpha3 apart, with the
    axes built by scipy rotations (independent of the equation's algebra and of kinprop)."""
    t = np.radians(np.arange(0.0, 360.0, 7.0))
    for branch in (-1, +1):
        u2, u3 = spherical_axes(t, spherical_phi(t, branch=branch))
        assert np.abs(np.einsum("ij,ij->i", u2, u3) - np.cos(SPHERICAL[2])).max() < 1e-14
    # the two roots are distinct assemblies everywhere (crank-rocker: no toggle)
    gap = np.degrees(np.abs(wrap(spherical_phi(t) - spherical_phi(t, branch=+1))))
    assert gap.min() > 30.0


def test_spherical_example_is_assembled_on_the_closed_form():
    m = load_solved("spherical_fourbar.yaml")
    mob = kp.mobility(m)
    assert mob.mobility == 1 and mob.n_constraints == 2 and not mob.redundant
    t, phi = m.coordinates["O2"][0], m.coordinates["O4"][0]
    assert np.degrees(abs(wrap(phi - spherical_phi(t)))) < TOL_DEG
    # the coupler's axis from kinprop's kinematics (the cut's point) is the closed form's u3
    _, u3 = spherical_axes(t, phi)
    kin = compile_engine(m.mechanism).kinematics(m.design, m.coordinates)
    assert np.allclose(kin.A["coupler"] @ np.asarray(m.design["B.s_i"]), u3[0], atol=1e-10)
    assert np.allclose(kin.A["output"] @ m.design["B.C_j"][:, 2], u3[0], atol=1e-10)


def test_offset_slider_example_is_assembled_on_the_closed_form():
    m = load_solved("slider_crank_offset.yaml")
    mob = kp.mobility(m)
    assert mob.mobility == 1 and mob.n_constraints == 2 and not mob.redundant
    t, x, psi = m.coordinates["O2"][0], m.coordinates["P"][0], m.coordinates["A"][0]
    r, l, e = OFFSET_SLIDER
    assert abs(x - slider_x(t)) < 1e-12
    # the rod's end B = A + l (cos, sin)(theta + psi) is on the slider line y = e at x
    B = r * np.array([np.cos(t), np.sin(t)]) + l * np.array([np.cos(t + psi), np.sin(t + psi)])
    assert np.allclose(B, [x, e], atol=1e-12)


# --- default-mode sweeps at coarse steps -------------------------------------------------------
def _fr(lengths, br):
    return lambda t: freudenstein(*lengths, t, branch=br)


SWEEPS = {
    # name: (model file or None for the RSSR builder, drive joint, range [deg], output column,
    #        closed form, other root, smallest distance to the other root [deg or m])
    "crank-rocker": ("fourbar.yaml", "O2", (0, 360), "O4.q", _fr(CRANK_ROCKER, -1), _fr(CRANK_ROCKER, +1), 10.0),
    "double-rocker": ("fourbar_double_rocker.yaml", "O2", (-135, 135), "O4.q", _fr(DOUBLE_ROCKER, -1),
                      _fr(DOUBLE_ROCKER, +1), 10.0),
    "spherical": ("spherical_fourbar.yaml", "O2", (0, 360), "O4.q", spherical_phi,
                  lambda t: spherical_phi(t, branch=+1), 30.0),
    "bennett": ("bennett.yaml", "J1", (-180, 180), "J2.q", bennett_theta2, None, 0.0),
    "slider": ("slider_crank_offset.yaml", "O2", (0, 360), "P.q", slider_x, lambda t: slider_x(t, branch=-1), 0.5),
    "rssr": (None, "crank", (0, 360), "rocker.q", lambda t: _rssr(t, _rssr_length(rssr())),
             lambda t: _rssr(t, _rssr_length(rssr()), -1), 60.0),
}  # fmt: skip


def _sweep_params():
    out = []
    for name in SWEEPS:
        for direction in ("up", "down"):
            for step in (30, 45):
                key = (name, direction, step)
                out.append(pytest.param(*key, id=f"{name}-{direction}-{step}"))
    return out


@pytest.mark.parametrize(("name", "direction", "step"), _sweep_params())
def test_coarse_sweep_stays_on_the_start_branch(name, direction, step):
    """kp.sweep in default mode by 30 and 45 deg steps, up and down: every step on the closed
    form's root of the start configuration (the model file's estimates), the other root far."""
    file, joint, (lo, hi), col, exact, other, gap = SWEEPS[name]
    n = round((hi - lo) / step)
    hi = lo + n * step
    if direction == "down":
        lo, hi = hi, lo
    if file is None:  # the RSSR builder's model is in radians
        res = kp.sweep(
            rssr(), [f"{joint}={float(np.radians(lo))!r}:{float(np.radians(hi))!r}:{n}"], outputs=[], tol=1e-12
        )
        t, out = res.frame[f"{joint}.q"], res.frame[col]
    else:
        res = kp.sweep(load_model(EXAMPLES / file), [f"{joint}={lo}:{hi}:{n}"], outputs=[], tol=1e-12)
        t = np.radians(res.frame[f"{joint}.q"])
        out = res.frame[col] if name == "slider" else np.radians(res.frame[col])
    assert res.ok and len(res.frame) == n + 1

    def dist(x, y):
        return np.abs(x - y) if name == "slider" else np.degrees(np.abs(wrap(x - y)))

    err = dist(out, exact(t))
    assert err.max() < (1e-12 if name == "slider" else TOL_DEG), (name, direction, step, np.round(err, 3).tolist())
    if other is not None:  # the other root is far at every step: a branch switch cannot pass
        assert dist(out, other(t)).min() > gap
    if name == "bennett":  # theta3 = -theta1 on the same circuit
        assert np.degrees(np.abs(wrap(np.radians(res.frame["J3.q"]) + t))).max() < TOL_DEG


# --- large single propagations ------------------------------------------------------------------
def _case(name: str):
    """(solved model, input joint, free, output joint, closed form of the output, other root)."""
    if name == "crank-rocker":
        f = lambda t, br=-1: freudenstein(*CRANK_ROCKER, t, branch=br)  # noqa: E731
        return load_solved("fourbar.yaml"), "O2", ("A.q", "O4.q"), "O4", f
    if name == "double-rocker":
        f = lambda t, br=-1: freudenstein(*DOUBLE_ROCKER, t, branch=br)  # noqa: E731
        return load_solved("fourbar_double_rocker.yaml"), "O2", ("A.q", "O4.q"), "O4", f
    if name == "spherical":
        return (
            load_solved("spherical_fourbar.yaml"),
            "O2",
            ("A.q", "O4.q"),
            "O4",
            lambda t, br=-1: spherical_phi(t, branch=br),
        )
    if name == "slider":
        return (
            load_solved("slider_crank_offset.yaml"),
            "O2",
            ("A.q", "P.q"),
            "P",
            lambda t, br=+1: slider_x(t, branch=br),
        )
    if name == "rssr":
        m = rssr()
        L = _rssr_length(m)
        return m, "crank", ("rocker.q",), "rocker", lambda t, br=+1: _rssr(t, L, br)
    if name == "bennett":
        return load_solved("bennett.yaml"), "J1", ("J2.q", "J3.q"), "J2", lambda t, br=0: bennett_theta2(t)
    raise KeyError(name)


def _distance(name: str, a: float, b: float) -> float:
    """|a - b| in metres (slider) or degrees (angles, wrapped)."""
    return abs(a - b) if name == "slider" else float(np.degrees(abs(wrap(a - b))))


TURNS = [
    ("crank-rocker", 150), ("crank-rocker", -150), ("crank-rocker", 120), ("double-rocker", -150),
    ("double-rocker", -120), ("spherical", 150), ("spherical", -90), ("spherical", 170), ("slider", 90),
    ("slider", 150), ("rssr", 150), ("rssr", -150), ("bennett", 150), ("bennett", -170),
]  # fmt: skip


@pytest.mark.parametrize(
    ("name", "delta"),
    TURNS,
)
def test_large_input_turn_in_one_call_lands_on_the_start_branch(name, delta):
    """The input turned by ``delta`` degrees in ONE kp.propagate call (default mode); in solver
    units (radians), as the closed forms are."""
    m, inp, free, out, exact = _case(name)
    t = float(m.coordinates[inp][0]) + np.radians(delta)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = kp.propagate(m, {f"{inp}.q": [t]}, free, tol=1e-12, units="solver")
    assert prop.converged, prop.result.message
    got = float(prop.after.coordinates[out][0])
    tol = 1e-12 if name == "slider" else TOL_DEG
    assert _distance(name, got, exact(t)) < tol, (name, delta, _distance(name, got, exact(t)))


@pytest.mark.parametrize(("name", "delta", "other_deg"), [("crank-rocker", 150, 95.25), ("spherical", 150, 100.20)])
def test_plain_newton_lands_on_the_other_branch_the_default_does_not(name, delta, other_deg):
    """Proof that the checks above catch a switch: the paper's plain Newton (branch=False) lands
    on the other root of the same closed form, ``other_deg`` degrees away."""
    m, inp, free, out, exact = _case(name)
    t = float(m.coordinates[inp][0]) + np.radians(delta)
    plain = kp.propagate(m, {f"{inp}.q": [t]}, free, tol=1e-12, branch=False, units="solver")
    default = kp.propagate(m, {f"{inp}.q": [t]}, free, tol=1e-12, units="solver")
    assert plain.converged and default.converged
    p, d = float(plain.after.coordinates[out][0]), float(default.after.coordinates[out][0])
    assert _distance(name, p, exact(t, -1)) == pytest.approx(other_deg, abs=0.01)
    assert _distance(name, p, exact(t, +1)) < TOL_DEG
    assert _distance(name, d, exact(t, -1)) < TOL_DEG


def test_turn_past_the_input_limit_in_one_call_is_infeasible():
    """Double rocker from 60 deg to 150 deg (limit 137.87 deg): no pose, the fraction reached
    is at most the exact one (137.87 - 60) / 90 = 0.865."""
    m, _, free, _, _ = _case("double-rocker")
    t0 = float(m.coordinates["O2"][0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = kp.propagate(m, {"O2.q": [t0 + np.radians(90.0)]}, free, tol=1e-12, units="solver")
    assert not prop.converged and prop.result.status == "infeasible"
    frac = float(re.search(r"only to ([0-9.e-]+)", prop.result.message).group(1))
    exact_frac = (input_limit(*DOUBLE_ROCKER) - t0) / np.radians(90.0)
    assert 0.5 < frac <= exact_frac + 1e-9, (frac, exact_frac)


# --- large link-length changes ------------------------------------------------------------------
@pytest.mark.parametrize("crank_deg", [60, 150, 240])
@pytest.mark.parametrize(
    ("key", "index", "factor"),
    [("A.s_i[0]", 0, 1.4), ("B.s_i[0]", 1, 1.4), ("B.s_j[0]", 2, 0.6), ("O4.s_i[0]", 3, 1.4), ("B.s_i[0]", 1, 0.6)],
)
def test_forty_percent_link_change_four_bar(crank_deg, key, index, factor):
    m = set_crank(load_solved("fourbar.yaml"), crank_deg)
    lengths = list(CRANK_ROCKER)
    lengths[index] *= factor
    t = m.coordinates["O2"][0]
    prop = kp.propagate(m, {key: lengths[index]}, ("A.q", "O4.q"), tol=1e-12)
    assert prop.converged
    got = prop.after.coordinates["O4"][0]
    assert np.degrees(abs(wrap(got - freudenstein(*lengths, t)))) < TOL_DEG
    assert np.degrees(abs(wrap(got - freudenstein(*lengths, t, branch=+1)))) > 10.0


@pytest.mark.parametrize(
    ("file", "lengths", "other_deg"),
    [("fourbar.yaml", CRANK_ROCKER, 61.36), ("fourbar_double_rocker.yaml", DOUBLE_ROCKER, 137.14)],
)
def test_forty_percent_ground_change_plain_newton_jumps_the_default_does_not(file, lengths, other_deg):
    """Input at -20 deg, ground link d 40 % shorter in one call: the paper's plain Newton lands on
    Freudenstein's crossed root (``other_deg`` away), the default on the open one."""
    m = set_input(load_solved(file), "O2", -20.0, ("A.q", "O4.q"))
    new = (*lengths[:3], 0.6 * lengths[3])
    t = m.coordinates["O2"][0]
    plain = kp.propagate(m, {"O4.s_i[0]": new[3]}, ("A.q", "O4.q"), tol=1e-12, branch=False)
    default = kp.propagate(m, {"O4.s_i[0]": new[3]}, ("A.q", "O4.q"), tol=1e-12)
    assert plain.converged and default.converged
    p, d = plain.after.coordinates["O4"][0], default.after.coordinates["O4"][0]
    assert np.degrees(abs(wrap(p - freudenstein(*new, t)))) == pytest.approx(other_deg, abs=0.01)
    assert np.degrees(abs(wrap(p - freudenstein(*new, t, branch=+1)))) < TOL_DEG
    assert np.degrees(abs(wrap(d - freudenstein(*new, t)))) < TOL_DEG


def test_forty_percent_changes_spherical_slider_rssr():
    # spherical: coupler arc alpha3 50 -> 70 deg and 50 -> 30 deg (the cut's point on the coupler)
    m = load_solved("spherical_fourbar.yaml")
    t = m.coordinates["O2"][0]
    for f in (1.4, 0.6):
        al = (SPHERICAL[0], SPHERICAL[1], f * SPHERICAL[2], SPHERICAL[3])
        prop = kp.propagate(m, {"B.s_i": [np.sin(al[2]), 0.0, np.cos(al[2])]}, ("A.q", "O4.q"), tol=1e-12)
        assert prop.converged
        assert np.degrees(abs(wrap(prop.after.coordinates["O4"][0] - spherical_phi(t, al)))) < TOL_DEG
    # offset slider-crank: rod 0.35 -> 0.49 and -> 0.21 m at four crank angles
    r, l, e = OFFSET_SLIDER
    m = load_solved("slider_crank_offset.yaml")
    for deg in (90, 180, 270, 360):
        m = set_input(m, "O2", deg, ("A.q", "P.q"))
        for f in (1.4, 0.6):
            prop = kp.propagate(m, {"B.s_i[0]": f * l}, ("A.q", "P.q"), tol=1e-12)
            assert (
                prop.converged and abs(prop.after.coordinates["P"][0] - slider_x(np.radians(deg), r, f * l, e)) < 1e-12
            )
    # RSSR: coupler 40 % shorter at crank 0 deg (the rocker turns 135 deg away from the other root)
    m = rssr()
    L = _rssr_length(m)
    prop = kp.propagate(m, {"coupler.length": 0.6 * L}, ("rocker.q",), tol=1e-12)
    assert prop.converged
    assert np.degrees(abs(wrap(prop.after.coordinates["rocker"][0] - _rssr(0.0, 0.6 * L)))) < TOL_DEG


def test_impossible_spherical_change_is_infeasible_not_a_jump():
    """Spherical four-bar at theta = 180 deg, coupler arc 50 -> 25 deg: there alpha3 >= |angle(u2, u4)
    - alpha4| = 75 - 45 = 30 deg, so the change can go to (50 - 30) / (50 - 25) = 0.8 of its size,
    no further (the S-T cut also admits the antipodal coupler axis -u3: never reachable continuously)."""
    m = set_crank(load_solved("spherical_fourbar.yaml"), 180.0)
    al3 = np.radians(25.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SingularityWarning)
        prop = kp.propagate(m, {"B.s_i": [np.sin(al3), 0.0, np.cos(al3)]}, ("A.q", "O4.q"), tol=1e-12)
    assert not prop.converged and prop.result.status == "infeasible", prop.result.message
    frac = float(re.search(r"only to ([0-9.e-]+)", prop.result.message).group(1))
    assert 0.79 < frac <= 0.8 + 1e-9  # measured 0.796923


# --- stepping back in after the toggle -----------------------------------------------------------
@pytest.mark.parametrize(
    "step",
    [
        30,
        45,
    ],
)
def test_double_rocker_out_past_the_limit_and_back_resumes_on_the_same_branch(step):
    """Drive step -> 225 -> step deg (input limit 137.87 deg): the steps past the limit fail, each
    saying how far it could be followed (at most the exact fraction to the limit, from the last
    good step); coming back inside the range the sweep resumes on the open branch."""
    limit = np.degrees(input_limit(*DOUBLE_ROCKER))
    out = np.arange(step, 225.0 + 1e-9, step)  # 225 deg is -135 deg: feasible, but behind the gap
    values = np.concatenate([out, out[-2::-1]])
    m = load_model(EXAMPLES / "fourbar_double_rocker.yaml")
    res = kp.sweep(m, [Drive("O2", 0, values, angle=True)], outputs=[], tol=1e-12)
    df = res.frame
    ok = df["status"] == "converged"
    beyond = df["O2.q"] > limit
    assert ok[~beyond].all() and (df.loc[beyond, "status"] == "infeasible").all()
    assert res.n_failed == int(beyond.sum()) >= 2
    assert df.loc[beyond, "O4.q"].isna().all()  # never a pose
    last_good = np.degrees(np.radians(df.loc[ok & (df["O2.q"] < limit), "O2.q"]).max())
    for _, row in df[beyond].iterrows():
        m_ = re.search(r"followed on the start's branch only to ([0-9.e-]+)", row["message"])
        assert m_, row["message"]
        exact = (limit - last_good) / (row["O2.q"] - last_good)
        assert float(m_.group(1)) <= exact + 1e-9
    back = df.index > df.index[beyond].max()
    assert back.sum() >= 3 and ok[back].all()
    t2 = np.radians(df.loc[ok, "O2.q"])
    t4 = np.radians(df.loc[ok, "O4.q"])
    assert np.degrees(np.abs(wrap(t4 - freudenstein(*DOUBLE_ROCKER, t2)))).max() < TOL_DEG
    assert np.degrees(np.abs(wrap(t4 - freudenstein(*DOUBLE_ROCKER, t2, branch=+1)))).min() > 10.0


def test_double_rocker_thirty_degree_step_down_to_zero():
    m = set_crank(load_solved("fourbar_double_rocker.yaml"), 30.0)
    prop = kp.propagate(m, {"O2.q": [0.0]}, ("A.q", "O4.q"), tol=1e-12)
    assert prop.converged
    err = np.degrees(abs(wrap(prop.after.coordinates["O4"][0] - freudenstein(*DOUBLE_ROCKER, 0.0))))
    assert err < TOL_DEG, err
