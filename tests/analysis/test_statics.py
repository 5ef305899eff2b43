"""Loads of assembled models (kp.statics) against closed forms and independent balances:
the four-bar's input torque for an output torque and for a coupler-point force (the loop's
velocity ratios by hand, Norton, *Design of Machinery*, sec. 6.7, and virtual work), the offset
slider-crank's input torque for a piston force, a redundant (all-revolute) planar four-bar
whose out-of-plane reactions are named undetermined while the in-plane ones match, and the
3D double wishbone's free-body balance of every moving body written here from the reported
reactions, element and applied forces."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import yaml

import kinprop as kp
from kinprop.analysis.metrics import contact_point
from kinprop.model.loads import LoadCase, PointLoad

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _assembled(source: str | Path | dict, tmp_path: Path | None = None) -> kp.Model:
    if isinstance(source, dict):
        assert tmp_path is not None
        f = tmp_path / "model.yaml"
        f.write_text(yaml.safe_dump(source))
        source = f
    return kp.assemble(kp.load_model(source), tol=1e-13).after


def _bodies_balance(s, loads=None) -> None:
    """Every moving body of a statics record balances: the reported joint forces and moments on
    it (moments about the reported points), the applied loads (rebuilt from the case), the
    elements' forces along their ends and the torsion springs' torques about their joints' axes
    sum to zero, forces and moments about the origin."""
    from kinprop.analysis.statics import _case, applied_points

    model = s.model
    kin = kp.compile(model).kinematics(model.design, model.coordinates)
    body = {b: np.zeros(6) for b in model.mechanism.body_names}
    for j in model.mechanism.joints:
        r = s.reactions[j.name]
        for side, b in enumerate((j.body_i, j.body_j)):
            body[b] += np.concatenate([r.force[side], r.moment[side] + np.cross(r.points[side], r.force[side])])
    W = applied_points(model, s.engine, s.state.r, s.state.A, _case(model, loads)).wrenches(len(body))
    for b, k in s.engine.body_index.items():
        body[b] += W[k]
    for e in model.elements:
        Pi = kin.r[e.body_i] + kin.A[e.body_i] @ np.array(e.s_i)
        Pj = kin.r[e.body_j] + kin.A[e.body_j] @ np.array(e.s_j)
        F = s.element_forces[e.name] * (Pj - Pi) / np.linalg.norm(Pj - Pi)
        body[e.body_j] += np.concatenate([F, np.cross(Pj, F)])
        body[e.body_i] -= np.concatenate([F, np.cross(Pi, F)])
    for t in model.torsion_springs:
        j = model.mechanism.joint(t.joint)
        M = s.element_forces[t.name] * kin.frames[t.joint].R_i[:, 2]
        body[j.body_j][3:] += M
        body[j.body_i][3:] -= M
    scale = max([1.0] + [float(np.linalg.norm(r.force[1])) for r in s.reactions.values()])
    size = max(1.0, float(np.max(np.abs(s.state.P))))
    for b in model.mechanism.bodies:
        if not b.fixed:
            assert np.linalg.norm(body[b.name][:3]) < 1e-9 * scale, b.name
            assert np.linalg.norm(body[b.name][3:]) < 1e-9 * scale * size, b.name


def _angle(A: np.ndarray) -> float:
    return math.atan2(A[1, 0], A[0, 0])


def _fourbar_ratios(model: kp.Model) -> tuple[float, float, dict[str, np.ndarray]]:
    """``(w3/w2, w4/w2)`` of the four-bar by hand: a e^{i t2} + b e^{i t3} - c e^{i t4} - d = 0
    differentiated (Norton eq. 6.18); the angles checked against the loop closure first."""
    kin = kp.compile(model).kinematics(model.design, model.coordinates)
    t2, t3, t4 = (_angle(kin.A[b]) for b in ("crank", "coupler", "rocker"))
    a, b, c, d = 0.15, 0.40, 0.30, 0.40
    loop = a * np.exp(1j * t2) + b * np.exp(1j * t3) - c * np.exp(1j * t4) - d
    assert abs(loop) < 1e-12
    w3 = a * math.sin(t4 - t2) / (b * math.sin(t3 - t4))
    w4 = a * math.sin(t2 - t3) / (c * math.sin(t4 - t3))
    return w3, w4, {"t2": t2, "t3": t3, "t4": t4}


@pytest.mark.parametrize("crank_deg", [60.0, 150.0, 250.0])
def test_fourbar_input_torque_closed_form(crank_deg: float) -> None:
    base = _assembled(EXAMPLES / "fourbar.yaml")
    model = kp.propagate(base, {"O2.q": crank_deg}, free=["q"], tol=1e-13).after
    w3, w4, ang = _fourbar_ratios(model)
    T4 = 12.5  # N m on the rocker, counter-clockwise
    s = kp.statics(model, PointLoad("rocker", (0.0, 0.0, 0.0), moment=(0.0, 0.0, T4)))
    assert s.ok
    _bodies_balance(s, PointLoad("rocker", (0.0, 0.0, 0.0), moment=(0.0, 0.0, T4)))
    assert s.efforts["O2.q"] == pytest.approx(-T4 * w4, rel=1e-10)
    # a force at the coupler point P (0.2, 0.1 in the coupler frame): v_P = v_A + w3 x (P - A)
    F = np.array([30.0, -45.0, 0.0])
    s = kp.statics(model, PointLoad("coupler", "P", force=tuple(F)))
    _bodies_balance(s, PointLoad("coupler", "P", force=tuple(F)))
    t2, t3 = ang["t2"], ang["t3"]
    vA = 0.15 * np.array([-math.sin(t2), math.cos(t2), 0.0])
    rel = np.array([0.2 * math.cos(t3) - 0.1 * math.sin(t3), 0.2 * math.sin(t3) + 0.1 * math.cos(t3), 0.0])
    vP = vA + np.cross([0.0, 0.0, w3], rel)
    assert s.efforts["O2.q"] == pytest.approx(-F @ vP, rel=1e-10)
    # the rocker is a two-force member under the coupler load: its pin force at O4 along O4-B
    B = s.reactions["B"].points[1]
    F4 = s.reactions["O4"].force[1]
    u = (B - s.reactions["O4"].points[1]) / np.linalg.norm(B - s.reactions["O4"].points[1])
    assert abs(F4[0] * u[1] - F4[1] * u[0]) < 1e-10 * np.linalg.norm(F4)


@pytest.mark.parametrize("crank_deg", [30.0, 100.0, 200.0, 300.0])
def test_offset_slider_crank_input_torque_closed_form(crank_deg: float) -> None:
    base = _assembled(EXAMPLES / "slider_crank_offset.yaml")
    model = kp.propagate(base, {"O2.q": crank_deg}, free=["q"], tol=1e-13).after
    t = math.radians(crank_deg)
    a, b, e = 0.10, 0.35, 0.05
    root = math.sqrt(b**2 - (e - a * math.sin(t)) ** 2)
    dx = -a * math.sin(t) + (e - a * math.sin(t)) * a * math.cos(t) / root
    Fx = -800.0  # gas force on the piston, towards the crank
    s = kp.statics(model, PointLoad("slider", (0.0, 0.0, 0.0), force=(Fx, 0.0, 0.0)), inputs=["O2"])
    _bodies_balance(s, PointLoad("slider", (0.0, 0.0, 0.0), force=(Fx, 0.0, 0.0)))
    assert s.efforts["O2.q"] == pytest.approx(-Fx * dx, rel=1e-10)
    # the connecting rod is a two-force member: the pin force at A on the rod is along A-B
    A_, B_ = s.reactions["A"].points[1], s.reactions["B"].points[0]
    FA = s.reactions["A"].force[1]
    u = (B_ - A_) / np.linalg.norm(B_ - A_)
    assert np.linalg.norm(np.cross(FA, u)) < 1e-10 * np.linalg.norm(FA)


def test_redundant_planar_fourbar_names_undetermined_components(tmp_path: Path) -> None:
    """All four joints revolute: three redundant rows (the out-of-plane reactions). The
    in-plane forces and the torques about the pins are determined (and equal the
    non-redundant model's); the out-of-plane force and the moments about in-plane axes are
    named undetermined and reported NaN, never a least-squares split."""
    data = yaml.safe_load((EXAMPLES / "fourbar.yaml").read_text())
    data["joints"]["B"] = {"type": "revolute", "bodies": ["coupler", "rocker"], "cut": True,
                           "s_i": [0.40, 0, 0], "s_j": [0.30, 0, 0]}  # fmt: skip
    redundant = _assembled(data, tmp_path)
    plain = _assembled(EXAMPLES / "fourbar.yaml")
    load = PointLoad("coupler", "P", force=(30.0, -45.0, 0.0), moment=(0.0, 0.0, 2.0))
    s, ref = kp.statics(redundant, load), kp.statics(plain, load)
    assert s.ok and s.undetermined
    assert "self-stress" in s.message
    assert s.efforts["O2.q"] == pytest.approx(ref.efforts["O2.q"], rel=1e-10)
    comps = {u.split(".")[1] for u in s.undetermined}
    assert comps <= {"fz", "mx", "my"}
    for j in ("O2", "A", "B", "O4"):
        r, r0 = s.reactions[j], ref.reactions[j]
        inplane = [0, 1, 5]  # fx, fy, mz in the joint frame (z'' along global z)
        assert not np.isnan(r.local[:, inplane]).any(), j
        assert np.allclose(r.local[:, inplane], r0.local[:, inplane], atol=1e-9 * 100), j
        for c in r.undetermined:
            assert np.isnan(r.local[1, ("fx", "fy", "fz", "mx", "my", "mz").index(c)])
    assert any(u.endswith(".fz") for u in s.undetermined)


def _dw_balance(model: kp.Model, s) -> None:
    """Every moving body: the reported joint forces and moments on it, the element forces
    (recomputed here from the element's ends and reported force) and the applied loads sum to
    zero; every joint's reactions are equal and opposite."""
    kin = kp.compile(model).kinematics(model.design, model.coordinates)
    scale = max(np.linalg.norm(r.force[1]) for r in s.reactions.values())
    L = 1000.0
    for body in ("lca", "uca", "upright"):
        F, M = np.zeros(3), np.zeros(3)  # about the global origin
        for j in model.mechanism.joints:
            for side, b in enumerate((j.body_i, j.body_j)):
                if b == body:
                    r = s.reactions[j.name]
                    F += r.force[side]
                    M += r.moment[side] + np.cross(r.points[side], r.force[side])
        for e in model.elements:
            Pi = kin.r[e.body_i] + kin.A[e.body_i] @ np.array(e.s_i)
            Pj = kin.r[e.body_j] + kin.A[e.body_j] @ np.array(e.s_j)
            u = (Pj - Pi) / np.linalg.norm(Pj - Pi)
            f = s.element_forces[e.name]
            if e.body_j == body:
                F += f * u
                M += np.cross(Pj, f * u)
            if e.body_i == body:
                F -= f * u
                M -= np.cross(Pi, f * u)
        applied = s.state.applied[s.engine.body_index[body]]
        # the applied wrench minus the elements' (recomputed above): the loads alone
        W_el = np.zeros(6)
        for e in model.elements:
            Pi = kin.r[e.body_i] + kin.A[e.body_i] @ np.array(e.s_i)
            Pj = kin.r[e.body_j] + kin.A[e.body_j] @ np.array(e.s_j)
            fu = s.element_forces[e.name] * (Pj - Pi) / np.linalg.norm(Pj - Pi)
            if e.body_j == body:
                W_el += np.concatenate([fu, np.cross(Pj, fu)])
            if e.body_i == body:
                W_el -= np.concatenate([fu, np.cross(Pi, fu)])
        F += applied[:3] - W_el[:3]
        M += applied[3:] - W_el[3:]
        assert np.linalg.norm(F) < 1e-9 * scale, body
        assert np.linalg.norm(M) < 1e-9 * scale * L, body
    for name, r in s.reactions.items():
        assert np.allclose(r.force[0], -r.force[1], atol=1e-9 * scale), name
        if np.allclose(r.points[0], r.points[1], atol=1e-9):
            assert np.allclose(r.moment[0], -r.moment[1], atol=1e-9 * scale * L), name


def test_double_wishbone_free_bodies_balance() -> None:
    model = _assembled(EXAMPLES / "double_wishbone.yaml")
    Fw = np.array([-4000.0, 2500.0, 9000.0])  # braking, cornering, vertical (ISO 8855, N)
    s = kp.statics(model, LoadCase("combined", wheels={"upright": tuple(Fw)}))
    assert s.ok and not s.undetermined
    # the applied load is the wheel force at the contact point (recomputed here)
    kin = kp.compile(model).kinematics(model.design, model.coordinates)
    pts = dict(model.mechanism.body("upright").points)
    centre = kin.r["upright"] + kin.A["upright"] @ np.array(pts["wheel_centre"])
    axis = kin.A["upright"] @ (np.array(pts["spin_axis"]) - np.array(pts["wheel_centre"]))
    radius = np.linalg.norm(np.array(pts["contact_patch"]) - np.array(pts["wheel_centre"]))
    Pc = contact_point(centre, axis, radius)
    b = s.engine.body_index["upright"]
    assert np.allclose(s.state.applied[b, :3], Fw)
    assert np.allclose(s.state.applied[b, 3:], np.cross(Pc, Fw), rtol=1e-12, atol=1e-6)
    _dw_balance(model, s)
    # joints: ball joints carry no moment; the upper arm's revolute no moment about its axis,
    # the lower arm's the input effort; the tie rod a force along its line
    scale = np.linalg.norm(Fw) * 1000.0
    for j in ("LBJ", "UBJ"):
        assert np.linalg.norm(s.reactions[j].moment[1]) < 1e-9 * scale
    fr = kin.frames
    assert abs(s.reactions["UCA"].moment[1] @ fr["UCA"].R_i[:, 2]) < 1e-9 * scale
    assert s.reactions["LCA"].moment[1] @ fr["LCA"].R_i[:, 2] == pytest.approx(s.efforts["LCA.q"], rel=1e-10)
    tr = s.reactions["TR"]
    u = (tr.points[1] - tr.points[0]) / np.linalg.norm(tr.points[1] - tr.points[0])
    assert np.linalg.norm(np.cross(tr.force[1], u)) < 1e-9 * np.linalg.norm(Fw)
    assert s.member_forces["TR"] == pytest.approx(-tr.force[1] @ u, rel=1e-12)
    # the spring's force from its stiffness and free length at the recomputed length
    e = model.element("spring")
    Pi = kin.r[e.body_i] + kin.A[e.body_i] @ np.array(e.s_i)
    Pj = kin.r[e.body_j] + kin.A[e.body_j] @ np.array(e.s_j)
    assert s.element_forces["spring"] == pytest.approx(e.stiffness * (e.free_length - np.linalg.norm(Pj - Pi)))
    assert s.element_forces["shock"] == 0.0


def test_tie_rod_tension_sign() -> None:
    """Tension positive: a positive member force pulls body j towards body i (a longitudinal
    wheel force ahead of the steering axis loads the tie rod)."""
    model = _assembled(EXAMPLES / "double_wishbone.yaml")
    s = kp.statics(model, LoadCase("steer", wheels={"upright": (2000.0, 0.0, 0.0)}))
    tr = s.reactions["TR"]
    towards_i = tr.points[0] - tr.points[1]
    assert np.sign(tr.force[1] @ towards_i) == np.sign(s.member_forces["TR"])
    assert abs(s.member_forces["TR"]) > 1.0


def test_loads_as_outputs() -> None:
    """``reaction:``, ``force:``, ``effort:`` outputs (``@CASE``) are kp.statics' numbers, with
    their units; unknown joints, components, elements and cases are refused by name."""
    from kinprop.analysis.outputs import evaluate_outputs
    from kinprop.analysis.units import unit_of
    from kinprop.errors import AddressError

    base = _assembled(EXAMPLES / "double_wishbone.yaml")
    model = kp.propagate(base, {"LCA.q": 4.0}, free=["q"], tol=1e-13).after
    names = ["reaction:UBJ.fz@bump_3g", "reaction:LCA.local.mz@bump_3g", "force:TR@braking_1g", "force:spring",
             "effort:LCA@cornering_1g"]  # fmt: skip
    got = evaluate_outputs(model, names)
    s = {c: kp.statics(model, c) for c in ("bump_3g", "braking_1g", "cornering_1g")}
    tol = 1e-10 * 3e4  # round-off of the largest reaction (the engines' scalings differ)
    assert got["reaction:UBJ.fz@bump_3g"] == pytest.approx(s["bump_3g"].reactions["UBJ"].force[1][2], abs=tol)
    assert got["reaction:LCA.local.mz@bump_3g"] == pytest.approx(s["bump_3g"].efforts["LCA.q"], rel=1e-9)
    assert got["force:TR@braking_1g"] == pytest.approx(s["braking_1g"].member_forces["TR"], abs=tol)
    assert got["force:spring"] == pytest.approx(s["bump_3g"].element_forces["spring"], rel=1e-12)
    assert got["effort:LCA@cornering_1g"] == pytest.approx(s["cornering_1g"].efforts["LCA.q"], rel=1e-10)
    assert [unit_of(model, n) for n in names] == ["N", "N mm", "N", "N", "N mm"]
    for bad in ("reaction:NOPE.fz", "reaction:UBJ.fw", "force:nope", "effort:UCA", "force:TR@nope"):
        with pytest.raises((AddressError, KeyError)):
            evaluate_outputs(model, [bad])


LEVER = {
    "kinprop": 1,
    "name": "spring-loaded lever",
    "units": {"length": "m", "angle": "deg", "force": "N"},
    "bodies": {
        "ground": {"fixed": True, "points": {"anchor": [0.3, 0.5, 0.0]}},
        "lever": {"points": {"tip": [0.8, 0, 0]}},
    },
    "joints": {"O": {"type": "revolute", "bodies": ["ground", "lever"], "s_i": [0, 0, 0], "q": [10.0]}},
    "inputs": ["O"],
    "elements": {"spring": {"type": "spring", "bodies": ["ground", "lever"], "s_i": [0.3, 0.5, 0.0],
                            "s_j": [0.6, 0.0, 0.0], "stiffness": 2000.0, "free_length": 0.45}},
}  # fmt: skip


def _lever_tau(theta: float, Fy: float) -> float:
    """Effort holding the lever at ``theta`` (rad) against the spring and a force Fy at the tip, by hand."""
    c, s = math.cos(theta), math.sin(theta)
    anchor, Pj, dPj = np.array([0.3, 0.5]), 0.6 * np.array([c, s]), 0.6 * np.array([-s, c])
    d = Pj - anchor
    L = np.linalg.norm(d)
    f = 2000.0 * (0.45 - L)  # pushing apart
    power = f * (d / L) @ dPj + Fy * 0.8 * c  # spring on the lever + tip force, per unit rate
    return -power


def test_equilibrium_of_a_spring_loaded_lever(tmp_path: Path) -> None:
    """The equilibrium angle against a root of the hand-written effort (scipy's brentq)."""
    import scipy.optimize

    from kinprop.analysis.statics import equilibrium

    model = _assembled(LEVER, tmp_path)
    Fy = -150.0
    e = equilibrium(model, PointLoad("lever", "tip", force=(0.0, Fy, 0.0)))
    assert e.converged, e.message
    theta = float(e.model.coordinates["O"][0])  # a Model keeps coordinates in radians
    truth = scipy.optimize.brentq(lambda t: _lever_tau(t, Fy), theta - 0.3, theta + 0.3, xtol=1e-15)
    assert theta == pytest.approx(truth, abs=1e-10)
    assert abs(e.statics.efforts["O.q"]) < 1e-8
    _bodies_balance(e.statics, PointLoad("lever", "tip", force=(0.0, Fy, 0.0)))
    # the stiffness is the derivative of the hand-written effort
    h = 1e-6
    assert e.stiffness[0, 0] == pytest.approx(
        (_lever_tau(truth + h, Fy) - _lever_tau(truth - h, Fy)) / (2 * h), rel=1e-6
    )
    assert e.stable == (e.stiffness[0, 0] > 0)


def test_double_wishbone_equilibrium_and_wheel_rate() -> None:
    """Ride height under an 11 kN corner load: no effort left at the input, every body in
    balance; the wheel rate against central differences of the wheel-centre force that holds
    the springs (from statics at re-solved poses) over the wheel-centre travel."""
    from kinprop.analysis.statics import equilibrium, wheel_rate

    model = _assembled(EXAMPLES / "double_wishbone.yaml")
    e = equilibrium(model, LoadCase("corner", wheels={"upright": (0.0, 0.0, 11000.0)}))
    assert e.converged and e.stable, e.message
    assert abs(e.statics.efforts["LCA.q"]) < 1e-9 * 11000.0 * 1000.0
    _dw_balance(e.model, e.statics)

    def force_and_height(m: kp.Model) -> tuple[float, float]:
        springs = kp.statics(m).efforts["LCA.q"]
        with_unit = kp.statics(m, PointLoad("upright", "wheel_centre", force=(0.0, 0.0, 1.0))).efforts["LCA.q"]
        unit = with_unit - springs  # loads superpose: the effort of 1 N up at the wheel centre
        kin = kp.compile(m).kinematics(m.design, m.coordinates)
        z = (kin.r["upright"] + kin.A["upright"] @ np.array(dict(m.mechanism.body("upright").points)["wheel_centre"]))[
            2
        ]
        return -springs / unit, float(z)  # the vertical force at the wheel centre that replaces the input

    for m in (model, e.model):
        q0 = math.degrees(float(m.coordinates["LCA"][0]))  # propagate takes the model's unit

        def at(t: float, m: kp.Model = m, q0: float = q0) -> tuple[float, float]:
            return force_and_height(kp.propagate(m, {"LCA.q": q0 + t}, free=["q"], tol=1e-14).after)

        h = 1e-3  # degrees
        (f1, z1), (f0, z0) = at(h), at(-h)
        (g1, y1), (g0, y0) = at(h / 2), at(-h / 2)
        truth = (4 * (g1 - g0) / (y1 - y0) - (f1 - f0) / (z1 - z0)) / 3
        assert wheel_rate(m) == pytest.approx(truth, rel=1e-6)


def test_mcpherson_rods_carry_axial_forces() -> None:
    """The McPherson strut's lower arm (revolute-spherical link) and tie rod (translational-
    distance): each rod's tension from its distance row equals minus the reported force on
    the wheel along the rod (the ball end transmits no moment, the link only its axial force
    in its plane), and the wheel body balances."""
    model = _assembled(EXAMPLES / "mcpherson.yaml")
    F = np.array([-2000.0, 3000.0, 8000.0])
    s = kp.statics(model, PointLoad("wheel", (0.0, 0.0, 0.0), force=tuple(F)), inputs=["TD", "ST.q[4]"])
    assert s.ok and not s.undetermined
    _bodies_balance(s, PointLoad("wheel", (0.0, 0.0, 0.0), force=tuple(F)))
    kin = kp.compile(model).kinematics(model.design, model.coordinates)
    fr = kin.frames
    for name in ("RS", "TD"):
        r = s.reactions[name]
        Pi = fr[name].P_i + (fr[name].R_i[:, 2] * model.coordinates["TD"][0] if name == "TD" else 0.0)
        u = (r.points[1] - Pi) / np.linalg.norm(r.points[1] - Pi)
        assert s.member_forces[name] == pytest.approx(-r.force[1] @ u, rel=1e-9, abs=1e-9 * 8000)
        assert np.linalg.norm(r.moment[1]) < 1e-9 * 8000
    total = np.concatenate([F, np.zeros(3)])
    for j in model.mechanism.joints:
        r = s.reactions[j.name]
        total += np.concatenate([r.force[1], r.moment[1] + np.cross(r.points[1], r.force[1])])
    # the load acts at the wheel frame's origin: its moment about the global origin
    b = s.engine.body_index["wheel"]
    total[3:] += np.cross(s.state.r[b], F)
    assert np.allclose(total, 0.0, atol=1e-8 * 8000)


def test_wheel_forces_in_an_sae_model(tmp_path: Path) -> None:
    """The double wishbone turned upside down about x (SAE J670 axes: y right, z down) under
    the same ISO 8855 wheel force: the same input effort and member forces, every reaction
    the ISO one turned by Rx(180 deg)."""
    data = yaml.safe_load((EXAMPLES / "double_wishbone.yaml").read_text())
    data["units"]["axes"] = "SAE"
    data["bodies"]["chassis"]["orientation"] = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
    data.pop("loads")
    sae = _assembled(data, tmp_path)
    iso = _assembled(EXAMPLES / "double_wishbone.yaml")
    case = LoadCase("c", wheels={"upright": (-4000.0, 2500.0, 9000.0)})
    a, b = kp.statics(iso, case), kp.statics(sae, case)
    flip = np.array([1.0, -1.0, -1.0])
    assert b.efforts["LCA.q"] == pytest.approx(a.efforts["LCA.q"], rel=1e-9)
    assert b.member_forces["TR"] == pytest.approx(a.member_forces["TR"], rel=1e-9)
    for j in a.reactions:
        assert np.allclose(b.reactions[j].force[1], flip * a.reactions[j].force[1], rtol=1e-9, atol=1e-6)
        assert np.allclose(b.reactions[j].moment[1], flip * a.reactions[j].moment[1], rtol=1e-9, atol=1e-3)
    # the design derivatives (the contact point's motion in the z-mirrored axes) match too
    from kinprop.analysis.statics import load_derivatives
    from kinprop.propagation.sensitivity import design_sensitivity

    names, wrt = ["effort:LCA", "force:TR", "reaction:UBJ.fy"], ["UBJ.s_j[0]", "TR.length", "LBJ.s_i[2]"]
    D = []
    for m in (iso, sae):
        eng = kp.compile(m)
        sens = design_sensitivity(m, wrt, ["q"], engine=eng, units="solver")
        X = np.zeros((len(wrt), eng.n_columns))
        X[np.arange(len(wrt)), sens.wrt_columns] = 1.0
        X[:, sens.free_columns] = sens.matrix.T
        D.append(load_derivatives(m, names, X, engine=eng, loads=case))
    assert np.allclose(D[1], D[0] * np.array([1.0, 1.0, -1.0])[:, None], rtol=1e-8, atol=1e-6)
    assert np.all(np.abs(D[0][:2]) > 1.0)


def test_an_unassembled_model_has_no_loads() -> None:
    raw = kp.load_model(EXAMPLES / "slider_crank.yaml")  # estimates: J12 open by more than 1e-4
    s = kp.statics(raw, PointLoad("slider", (0.0, 0.0, 0.0), force=(100.0, 0.0, 0.0)))
    assert s.status == "not_assembled" and "assemble" in s.message
    assert all(np.isnan(r.force[1]).all() for r in s.reactions.values())


def _richardson_of_resolved(base: kp.Model, names: list[str], column: str, h: float, **propagate) -> np.ndarray:
    """d(outputs)/d(column) by Richardson central differences (steps h, h/2) of models
    re-solved with the design column changed (``kp.propagate``, model units)."""
    from kinprop.analysis.outputs import evaluate_outputs

    key, _, index = column.partition("[")
    x0 = float(np.atleast_1d(np.asarray(base.design[key], dtype=float)).ravel()[int(index[:-1]) if index else 0])

    def at(t: float) -> np.ndarray:
        m = kp.propagate(base, {column: x0 + t}, tol=1e-14, **propagate).after
        v = evaluate_outputs(m, names)
        return np.array([v[n] for n in names])

    def d(step: float) -> np.ndarray:
        return (at(step) - at(-step)) / (2 * step)

    return (4 * d(h / 2) - d(h)) / 3


def test_double_wishbone_design_derivatives_of_loads() -> None:
    """``output_sensitivity`` of reactions (global, joint-frame, magnitude), the tie rod's
    tension, the spring force and the input effort under the example's wheel load cases
    (contact-point forces, weights) with respect to hardpoints and a length: exact (the
    differentiated equilibrium, method 'direct') against central differences of re-solved
    models, in the model's units (N per mm, N mm per mm)."""
    from kinprop.analysis.sensitivity import DIRECT, output_sensitivity

    base = kp.propagate(_assembled(EXAMPLES / "double_wishbone.yaml"), {"LCA.q": 4.0}, tol=1e-14).after
    names = ["reaction:UBJ.fz@bump_3g", "reaction:LCA.local.mz@bump_3g", "reaction:LBJ.fx@cornering_1g",
             "reaction:UCA.my@braking_1g", "reaction:UCA.local.fx@braking_1g", "reaction:UBJ.f@bump_3g",
             "force:TR@braking_1g", "force:spring", "effort:LCA@cornering_1g"]  # fmt: skip
    wrt = ["UBJ.s_j[0]", "LBJ.s_i[2]", "TR.length", "UCA.s_i[1]"]
    D = output_sensitivity(base, names, wrt)
    assert set(D.attrs["method"].values()) == {DIRECT}
    for c in wrt:
        fd = _richardson_of_resolved(base, names, c, 0.1)
        scale = np.maximum(np.abs(fd), 1.0)
        assert np.all(np.abs(D[c].to_numpy() - fd) < 1e-7 * scale), (c, D[c].to_numpy(), fd)
    assert abs(D.loc["force:TR@braking_1g", "TR.length"]) > 10.0  # a real dependence, N per mm


def test_mcpherson_design_derivatives_of_loads() -> None:
    """The McPherson strut (S-T tree joint with Euler parameters, R-S and T-D cut rods) held at
    the rack and the strut slide under a force on the wheel: exact design derivatives
    (``load_derivatives`` along the propagation's state response) of the rods' tensions, the
    strut's reaction and the efforts against central differences of re-solved models."""
    from kinprop.analysis.statics import load_derivatives
    from kinprop.propagation.sensitivity import design_sensitivity

    base = _assembled(EXAMPLES / "mcpherson.yaml")
    inputs = ["TD", "ST.q[4]"]
    case = LoadCase("corner", (PointLoad("wheel", (0.02, 0.1, -0.3), force=(-2000.0, 3000.0, 8000.0)),))
    names = ["force:RS", "force:TD", "reaction:ST.fz", "reaction:ST.local.my", "reaction:RS.local.fy", "effort:TD",
             "effort:ST.q[4]"]  # fmt: skip
    wrt = ["RS.s_j[1]", "TD.length", "ST.s_i[2]", "RS.length", "TD.s_i[0]"]
    engine = kp.compile(base)
    sens = design_sensitivity(base, wrt, ["q"], engine=engine, units="solver")
    X = np.zeros((len(wrt), engine.n_columns))
    X[np.arange(len(wrt)), sens.wrt_columns] = 1.0
    X[:, sens.free_columns] = sens.matrix.T
    wrt = list(sens.columns)  # the design columns in the order of X
    s0 = kp.statics(base, case, inputs=inputs)
    assert s0.ok and not s0.undetermined
    D = load_derivatives(base, names, X, engine=engine, inputs=inputs, loads=case)
    for k, c in enumerate(wrt):
        key, _, index = c.partition("[")
        x0 = float(np.atleast_1d(np.asarray(base.design[key], dtype=float)).ravel()[int(index[:-1]) if index else 0])

        def at(t: float, c: str = c, x0: float = x0) -> np.ndarray:
            s = kp.statics(kp.propagate(base, {c: x0 + t}, tol=1e-14).after, case, inputs=inputs)
            return np.array([s.value(n) for n in names])

        h = 1e-4
        fd = (4 * (at(h / 2) - at(-h / 2)) / h - (at(h) - at(-h)) / (2 * h)) / 3
        scale = np.maximum(np.abs(fd), 1.0)
        assert np.all(np.abs(D[:, k] - fd) < 1e-6 * scale), (c, D[:, k], fd)


def _fourbar_with(tmp_path: Path, elements: dict, inputs: list[str] | None = None) -> kp.Model:
    source = yaml.safe_load((EXAMPLES / "fourbar.yaml").read_text())
    source["units"]["force"] = "N"
    source["elements"] = elements
    if inputs is not None:
        source["inputs"] = inputs
    return _assembled(source, tmp_path)


@pytest.mark.parametrize("crank_deg", [60.0, 150.0, 250.0])
def test_torsion_spring_by_virtual_work(tmp_path: Path, crank_deg: float) -> None:
    """A torsion spring on the rocker's pivot (``type: torsion``, 2 N m/deg, free at 70 deg):
    its torque from the joint angle, the crank's holding torque by virtual work ``-T w4/w2``
    (the loop's velocity ratio by hand), the pivot carrying no torque about its axis, the
    torque's unit and the angle reported as the spring's "length"."""
    from kinprop.analysis.units import unit_of

    base = _fourbar_with(tmp_path, {"bar": {"type": "torsion", "joint": "O4", "stiffness": 2.0, "free_angle": 70.0}})
    model = kp.propagate(base, {"O2.q": crank_deg}, tol=1e-13).after
    _, w4, ang = _fourbar_ratios(model)
    theta4 = math.degrees(ang["t4"]) % 360.0
    assert float(model.coordinates["O4"][0]) == pytest.approx(math.radians(theta4), abs=1e-12)
    s = kp.statics(model)
    _bodies_balance(s)
    T = 2.0 * (70.0 - theta4)
    assert s.element_forces["bar"] == pytest.approx(T, rel=1e-12)
    assert s.element_lengths["bar"] == pytest.approx(theta4, rel=1e-12)
    assert s.efforts["O2.q"] == pytest.approx(-T * w4, rel=1e-10)
    assert abs(s.reactions["O4"].local[1, 5]) < 1e-10 * abs(T)  # the spring carries the torque, not the pin
    assert unit_of(model, "force:bar") == "N m"


def test_torsion_spring_equilibrium(tmp_path: Path) -> None:
    """A torsion spring on the crank (the input released) against a couple on the rocker: the
    equilibrium angle against a root (scipy's brentq) of ``k (theta0 - theta2) + T4 w4`` written
    from the loop's velocity ratio by hand."""
    import scipy.optimize

    from kinprop.analysis.statics import equilibrium

    base = _fourbar_with(tmp_path, {"bar": {"type": "torsion", "joint": "O2", "stiffness": 0.5, "free_angle": 60.0}})
    T4 = -8.0
    e = equilibrium(base, PointLoad("rocker", (0.0, 0.0, 0.0), moment=(0.0, 0.0, T4)))
    assert e.converged, e.message

    def residual(theta2_deg: float) -> float:
        m = kp.propagate(base, {"O2.q": theta2_deg}, tol=1e-14).after
        return 0.5 * (60.0 - theta2_deg) + T4 * _fourbar_ratios(m)[1]

    got = math.degrees(float(e.model.coordinates["O2"][0]))
    truth = scipy.optimize.brentq(residual, got - 5.0, got + 5.0, xtol=1e-13)
    assert got == pytest.approx(truth, abs=1e-9)
    assert abs(got - 60.0) > 1.0  # the couple moved it
    assert e.statics.element_forces["bar"] == pytest.approx(0.5 * (60.0 - truth), rel=1e-8)
    _bodies_balance(e.statics, PointLoad("rocker", (0.0, 0.0, 0.0), moment=(0.0, 0.0, T4)))


def test_torsion_spring_preload_and_bad_input(tmp_path: Path) -> None:
    """A preload is the torque at the model's angle; a torsion spring needs a revolute or
    cylindrical joint and takes no bodies or ends (errors name the element and the field)."""
    from kinprop.errors import ModelError

    base = _fourbar_with(tmp_path, {"bar": {"type": "torsion", "joint": "O4", "stiffness": 2.0, "preload": 5.0}})
    assert kp.statics(base).element_forces["bar"] == pytest.approx(5.0, rel=1e-12)
    moved = kp.propagate(base, {"O2.q": 70.0}, tol=1e-13).after
    dtheta = math.degrees(float(moved.coordinates["O4"][0]) - float(base.coordinates["O4"][0]))
    assert kp.statics(moved, reference=base).element_forces["bar"] == pytest.approx(5.0 - 2.0 * dtheta, rel=1e-10)
    for spec, where, text in (
        ({"type": "torsion", "joint": "B", "stiffness": 1.0}, "elements.bar.joint", "revolute or cylindrical"),
        ({"type": "torsion", "joint": "NOPE", "stiffness": 1.0}, "elements.bar.joint", "unknown joint 'NOPE'"),
        ({"type": "torsion", "joint": "O4"}, "elements.bar.stiffness", "needs 'stiffness'"),
        ({"type": "torsion", "joint": "O4", "stiffness": 1.0, "bodies": ["ground", "rocker"]}, "elements.bar.bodies",
         "takes no 'bodies'"),
        ({"type": "spring", "bodies": ["ground", "rocker"], "s_i": [0, 0, 0], "s_j": [0, 0, 0], "stiffness": 1.0,
          "joint": "O4"}, "elements.bar.joint", "takes no 'joint'"),
    ):  # fmt: skip
        with pytest.raises(ModelError) as exc:
            _fourbar_with(tmp_path, {"bar": spec})
        assert where in str(exc.value) and text in str(exc.value), str(exc.value)


def test_torsion_spring_survives_writing(tmp_path: Path) -> None:
    from kinprop.io import model_from_data
    from kinprop.io.hardpoints import model_to_hardpoints
    from kinprop.io.writer import dump_model

    base = _fourbar_with(tmp_path, {"bar": {"type": "torsion", "joint": "O4", "stiffness": 2.0, "free_angle": 70.0}})
    dump_model(base, tmp_path / "out.yaml")
    assert kp.load_model(tmp_path / "out.yaml").torsion_springs == base.torsion_springs
    assert model_from_data(model_to_hardpoints(base)).torsion_springs == base.torsion_springs
    from kinprop.analysis.study import _model_from_payload, _model_payload

    assert _model_from_payload(_model_payload(base)).torsion_springs == base.torsion_springs


SLIDES = {
    "kinprop": 1,
    "name": "two slides in series and a spring across both",
    "units": {"length": "mm", "angle": "deg", "force": "N"},
    "bodies": {"ground": {"fixed": True}, "b1": {}, "b2": {}},
    "joints": {
        "J1": {"type": "translational", "bodies": ["ground", "b1"], "q": [100.0]},
        "J2": {"type": "translational", "bodies": ["b1", "b2"], "q": [60.0]},
    },
    "inputs": ["J1", "J2"],
    "elements": {
        "spring": {
            "type": "spring",
            "bodies": ["ground", "b2"],
            "s_i": [0, 0, 0],
            "s_j": [0, 0, 0],
            "stiffness": 20.0,
            "free_length": 100.0,
        }
    },
}


@pytest.mark.parametrize("w1", [1.0, 4.0])
def test_equilibrium_takes_the_least_change_in_a_neutral_direction(tmp_path: Path, w1: float) -> None:
    """Two released slides in series: the spring fixes only their sum (``K`` singular), so the
    equilibrium is a line; the least change in the propagation's metric splits the 60 mm
    correction in proportion to the weights (``dq_k = w_k c / sum w``), and the pose is not
    stable (neutral)."""
    from kinprop.analysis.statics import equilibrium

    model = _assembled(SLIDES, tmp_path)
    e = equilibrium(model, weights={"J1.q": w1})
    assert e.converged, e.message
    q1, q2 = (float(e.model.coordinates[j][0]) for j in ("J1", "J2"))
    assert q1 + q2 == pytest.approx(100.0, abs=1e-9)
    assert q1 - 100.0 == pytest.approx(-60.0 * w1 / (w1 + 1.0), abs=1e-9)
    assert e.statics.element_forces["spring"] == pytest.approx(0.0, abs=1e-9)
    assert not e.stable


def test_double_wishbone_equilibrium_design_derivatives() -> None:
    """The ride height's design derivatives (``dq_D/dp = -K^-1 dtau/dp``, exact) against
    central differences of equilibria of re-solved models, in the model's units (deg per mm)."""
    from kinprop.analysis.statics import equilibrium, equilibrium_sensitivity

    model = _assembled(EXAMPLES / "double_wishbone.yaml")
    case = LoadCase("corner", wheels={"upright": (0.0, 0.0, 11000.0)})
    e = equilibrium(model, case)
    assert e.converged
    wrt = ["UBJ.s_j[0]", "TR.length", "LBJ.s_i[2]"]
    D, released, columns = equilibrium_sensitivity(e, wrt, case, reference=model)
    assert released == ["LCA.q"]
    for k, c in enumerate(columns):
        key, _, index = c.partition("[")
        x0 = float(np.atleast_1d(np.asarray(model.design[key], dtype=float)).ravel()[int(index[:-1]) if index else 0])

        def at(t: float, c: str = c, x0: float = x0) -> float:
            m = kp.propagate(model, {c: x0 + t}, tol=1e-14).after
            eq = equilibrium(m, case)
            assert eq.converged
            return math.degrees(float(eq.model.coordinates["LCA"][0]))

        h = 0.1
        fd = (4 * (at(h / 2) - at(-h / 2)) / h - (at(h) - at(-h)) / (2 * h)) / 3
        assert D[0, k] == pytest.approx(fd, rel=1e-6, abs=1e-9), (c, D[0, k], fd)
    assert abs(D[0, columns.index("LBJ.s_i[2]")]) > 1e-3  # a real dependence (deg per mm)


def test_planar_double_wishbone_free_bodies_by_hand() -> None:
    """The four-bar as a planar double wishbone (crank = lower arm held at O2, coupler =
    upright, rocker = upper arm) under a force on the upright, solved by hand from free-body
    diagrams: the unloaded upper arm is a two-force member (its force on the upright at B
    along O4->B, tension T); moments about A on the upright give T; the upright's force balance
    the force at A; the lower arm's moments about O2 the holding torque; the pivots the rest."""
    model = _assembled(EXAMPLES / "fourbar.yaml")
    F = np.array([30.0, -45.0, 0.0])
    s = kp.statics(model, LoadCase("push", forces=(PointLoad("coupler", "P", force=tuple(F)),)))
    assert s.ok
    kin = kp.compile(model).kinematics(model.design, model.coordinates)
    fr = kin.frames
    O2, A, B, O4 = fr["O2"].P_i, fr["A"].P_i, fr["B"].P_i, fr["O4"].P_i
    P = kin.r["coupler"] + kin.A["coupler"] @ np.array(dict(model.mechanism.body("coupler").points)["P"])

    def cz(a: np.ndarray, b: np.ndarray) -> float:
        return float(a[0] * b[1] - a[1] * b[0])

    u = (B - O4) / np.linalg.norm(B - O4)
    T = cz(P - A, F) / cz(B - A, u)  # sum of moments about A on the upright: -T (B-A) x u + (P-A) x F = 0
    on_upright_B = -T * u  # the upper arm pulls the upright towards O4 when in tension
    on_upright_A = -F - on_upright_B
    tau = cz(A - O2, on_upright_A)  # moments about O2 on the lower arm (pushed with -on_upright_A at A)
    plane = slice(0, 2)
    atol = 1e-9 * np.linalg.norm(F)
    assert np.allclose(s.reactions["B"].force[0][plane], on_upright_B[plane], atol=atol)  # B: [coupler, rocker]
    assert np.allclose(s.reactions["A"].force[1][plane], on_upright_A[plane], atol=atol)  # A: [crank, coupler]
    # the lower arm: -on_upright_A at A, so its pivot carries on_upright_A
    assert np.allclose(s.reactions["O2"].force[1][plane], on_upright_A[plane], atol=atol)
    assert np.allclose(s.reactions["O4"].force[1][plane], on_upright_B[plane], atol=atol)  # the rocker's pivot
    assert s.efforts["O2.q"] == pytest.approx(tau, rel=1e-9)
