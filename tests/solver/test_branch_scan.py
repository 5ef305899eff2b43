"""Never a spurious root (issue 24, item 2): a cut joint's dot-1 rows also hold with its frame
turned (a slide by pi, a revolute with z_j = -z_i); the solver refuses those roots, and a large
single change lands where a fine sweep lands, or fails.

Truth: the offset slider-crank's closed form, and fine sweeps (``Engine.solve_sequence``, 1/120
of the change per step) of every declared input of the shipped examples and of seeded random
mechanisms.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from typer.testing import CliRunner

import kinprop as kp
from kinprop.cli import app
from kinprop.engine import compile
from kinprop.joints import joint_type
from kinprop.solver import newton
from random_mechanisms import random_mechanism

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")

OFFSET = """\
kinprop: 1
name: offset slider-crank (r=50, l=150, e=20 mm, crank at 30 deg)
style: hardpoints
units: {length: mm, angle: rad, axes: right-handed}
bodies: {ground: {fixed: true}, crank: {}, rod: {}, slider: {}}
joints:
  O: {type: revolute, bodies: [ground, crank], point: [0, 0, 0], axis: [0, 0, 1]}
  A: {type: revolute, bodies: [crank, rod], point: [43.30127018922193, 25.0, 0], axis: [0, 0, 1]}
  B: {type: revolute, bodies: [rod, slider], point: [193.217913694871, 20.0, 0], axis: [0, 0, 1]}
  P: {type: translational, bodies: [ground, slider], point: [193.217913694871, 20.0, 0], axis: [1, 0, 0]}
inputs: [O]
"""


def pin_x(theta: float, r: float = 50.0, rod: float = 150.0, e: float = 20.0) -> float:
    """Closed form of the offset slider-crank: the pin's x on the slider's line y = e."""
    return r * np.cos(theta) + np.sqrt(rod**2 - (e - r * np.sin(theta)) ** 2)


@pytest.fixture(scope="module")
def offset(tmp_path_factory):
    path = tmp_path_factory.mktemp("offset") / "slider.yaml"
    path.write_text(OFFSET)
    return kp.load_model(path)


def test_rigid_axes_of_the_joint_types():
    """The axis pairs a joint keeps parallel (entries of A''(q) that are 1 for every q)."""
    assert joint_type("revolute").rigid_axes == ((2, 2),)
    assert joint_type("cylindrical").rigid_axes == ((2, 2),)
    assert joint_type("translational").rigid_axes == ((0, 0), (1, 1), (2, 2))
    assert joint_type("fixed").rigid_axes == ((0, 0), (1, 1), (2, 2))
    for name in ("universal", "spherical", "spherical-translational", "revolute-spherical", "distance", "dot-1"):
        assert joint_type(name).rigid_axes == ()


@pytest.mark.parametrize("q", [2.88, 2.5, -2.9, 3.1])
def test_offset_slider_crank_never_lands_on_the_turned_slider(offset, q):
    """The issue's case: --set O.q=2.88 converged with the slider turned by pi (pin at x =
    -194.63 mm); now the pin is where the closed form puts it, or the solve fails."""
    p = kp.propagate(offset, {"O.q": q}, units="solver")
    if not p.converged:
        return
    R = p.bodies["slider"]["R"]
    assert R[0][0] == pytest.approx(1.0, abs=1e-9)  # the slider is not turned
    pin = kp.compile(p.after).kinematics(p.after.design, p.after.coordinates).frames["B"].P_i
    assert pin[0] == pytest.approx(pin_x(np.deg2rad(30.0) + q), abs=1e-6)
    assert pin[1] == pytest.approx(20.0, abs=1e-9)


def test_offset_slider_crank_cli(offset, tmp_path):
    path = tmp_path / "slider.yaml"
    path.write_text(OFFSET)
    r = CliRunner().invoke(app, ["propagate", str(path), "--set", "O.q=2.88", "--json"])
    if r.exit_code == 0:
        got = json.loads(r.stdout)
        assert got["bodies"]["slider"]["R"][0][0] == pytest.approx(1.0, abs=1e-9)
        assert got["hardpoints"]["B.i"][0] == pytest.approx(pin_x(np.deg2rad(30.0) + 2.88), abs=1e-6)
    else:
        assert r.exit_code == 1, r.output


def test_plain_newton_landing_turned_is_a_failure(offset):
    """branch=False (plain Newton, one solve) lands on the turned root (the pin at -194.63 mm):
    status infeasible with flag FLIPPED, never converged."""
    eng = compile(offset)
    sol = eng.propagate({"O.q": 2.88}, branch=False)
    pin = eng.kinematics(sol.state).frames["B"].P_i
    assert pin[0] == pytest.approx(-194.63, abs=0.01)  # where plain Newton goes
    assert sol.flags & newton.FLIPPED and sol.status == "infeasible" and not sol.converged
    assert "turned" in sol.message
    ok = eng.propagate({"O.q": 2.88})
    assert ok.converged and not ok.flags & newton.LEAST_CHANGE_FAILED


# --- large single changes against fine sweeps ----------------------------------------------------
SWEEP_STEPS = 120
CHANGES = (-2.6, -1.3, 1.3, 2.6)  # radians (slides: times the model's length scale / 4)


def scan(model, addresses, free=("q",)) -> list[str]:
    """Each address changed by each of :data:`CHANGES` in one solve, and in a fine sweep; the
    single solve converges only where the sweep does, and then on the same pose."""
    eng = compile(model)
    start = eng.reference
    bad = []
    for address in addresses:
        t = eng.target(address)
        q0 = float(eng.get(start, address).ravel()[0])
        jt = model.mechanism.joint(address.split(".")[0]).jtype
        unit = 1.0 if (t.index or 0) in jt.angle_indices else 0.25 * eng.length_scale
        for d in CHANGES:
            q1 = q0 + d * unit
            single = eng.propagate({address: q1}, free=free, start=start)
            Q, batch = eng.solve_sequence(start, [address], np.linspace(q0, q1, SWEEP_STEPS + 1)[1:], free=free)
            swept = bool(np.all(batch.converged))
            if not single.converged:
                continue
            if not swept:
                bad.append(f"{address} {q0:+.3f} -> {q1:+.3f}: single converged, the sweep failed")
            elif not np.allclose(single.state.Q, Q[-1], atol=1e-6):
                bad.append(f"{address} -> {q1:+.3f}: single {single.state.Q} vs sweep {Q[-1]}")
    return bad


EXAMPLES = ["bennett", "double_wishbone", "fourbar", "fourbar_double_rocker", "fourbar_geared", "fourbar_spatial"]


@pytest.mark.parametrize("name", EXAMPLES)
def test_examples_inputs_single_change_lands_where_the_sweep_lands(examples, name):
    model = kp.assemble(kp.load_model(examples / f"{name}.yaml")).after
    addresses = [f"{j}.q" for j in model.mechanism.inputs]
    assert not scan(model, addresses, free=("q",)) if addresses else True


def test_slider_cranks_single_change_lands_where_the_sweep_lands(examples, offset):
    sc = kp.assemble(kp.load_model(examples / "slider_crank.yaml")).after
    assert not scan(sc, ["J01.q"], free=("J03.q", "J32.q"))
    so = kp.assemble(kp.load_model(examples / "slider_crank_offset.yaml")).after
    assert not scan(so, ["O2.q"], free=("A.q", "P.q"))
    assert not scan(offset, ["O.q"])


def random_drivable(count: int = 16):
    """Seeded random mechanisms (single-coordinate tree joints and cut revolutes/slides) with the
    tree joints whose coordinate, held, leaves no freedom (a square regular free Jacobian)."""
    out = []
    for seed in range(count):
        rng = np.random.default_rng(seed)
        tree = [str(x) for x in rng.choice(["revolute", "translational", "universal", "spherical"], size=4)]
        cuts = [(str(rng.choice(["revolute", "translational", "cylindrical", "fixed"])), "ground")]
        rm = random_mechanism(1300 + seed, tree, cuts, assembled=True)
        eng = compile(rm.model)
        _, J = eng.evaluate(eng.reference)
        drivable = []
        for j in rm.mechanism.joints:
            if j.name in eng.topology.tree_joints and j.jtype.n_coordinates == 1:
                cols = eng.free_columns(("q",), [f"{j.name}.q"])
                Jf = J[:, cols]
                if Jf.shape[0] == Jf.shape[1] and np.linalg.matrix_rank(Jf) == Jf.shape[0]:
                    drivable.append(f"{j.name}.q")
        if drivable:
            out.append((rm, drivable))
    return out


@pytest.mark.parametrize("case", random_drivable(), ids=lambda c: f"seed{c[0].seed}")
def test_random_mechanisms_single_change_lands_where_the_sweep_lands(case):
    rm, addresses = case
    bad = scan(rm.model, addresses)
    assert not bad, f"{rm.describe()}\n" + "\n".join(bad)
