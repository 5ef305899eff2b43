"""The assembled Jacobian and the B/M/N twists against central finite differences.

Every column of ``Assembly.evaluate(design, coords)[1]`` is compared with central differences
of the residual, perturbing the variable the way the solver updates it
(:func:`kinprop.kinematics.layout.retract`):

* ``q``  additive; Euler-parameter blocks only along tangent directions ``dp`` with
  ``p . dp = 0`` at unit ``p`` (the paper's ``H = 2E(p)`` is exact there, not along ``p``);
* ``s'`` additive (body frame);
* ``C``  body-frame exponential map ``C <- exp_so3(eps e_k) @ C`` (the column is ``xi'_k``);
* ``l``  additive.

Frame of the spherical rows. The tree variables enter through the loop paths from the
junction only (eqs. 43-48): the paper drops the joints above the junction because
``Phi_z^_i + Phi_z^_j = 0``. That holds for every row invariant under a rigid motion of the loop
(dot-1, dot-2, distance) but not for the spherical rows ``d`` (global components), for which the
sum is ``[0, -tilde(d)]``: zero at assembly only. So ``J`` is, row for row, the exact derivative
of the residual with the spherical rows resolved in the junction body's frame,
``Phi_p = A_p^T d``, rotated back: ``J = A_p dPhi_p/dx`` (``A_p = I`` for a fixed junction or the
world). Newton with this ``J`` is exact Newton on ``Phi_p`` (same zeros, same norm) and is better
behaved than with ``dd/dx``, whose rigid-rotation columns are near-singular (~|d|). The checks
below use that residual; at an assembled state they also use the plain global residual.

The tree-joint twists (the paper's B, M, N of eq. 34-35) are checked on the body poses: a
column's finite-difference motion of every body below the joint is the global twist
``[dr + tilde(r) dpi ; dpi]`` and every other body stays put.
"""

from __future__ import annotations

import numpy as np
import pytest

from kinprop.engine import Engine as Assembly
from kinprop.kinematics.layout import column_labels
from kinprop.model import Body, Design, Joint, Mechanism, as_coordinates
from kinprop.spatial import euler_E, exp_so3, tilde
from kinprop.topology import WORLD
from oracle.forward import forward_kinematics, retract
from oracle.transforms import tree_joint_twists
from random_mechanisms import CUT_TYPES, LOOP_KINDS, TREE_TYPES, random_mechanism, suite_mechanisms

EPS = 1e-6
RTOL = 1e-6

#: the suite (some with couplings) and two with four couplings between revolutes and slides
MECHANISMS = suite_mechanisms(count=24, base_seed=1000) + [
    random_mechanism(
        seed,
        ["revolute", "translational", "revolute", "translational", "spherical"],
        [("revolute", "branch"), ("distance", "ground")],
        couplings=4,
    )
    for seed in (2000, 2007)
]
IDS = [f"seed{m.seed}" for m in MECHANISMS]


def directions(asm: Assembly, coords) -> list[tuple[str, np.ndarray]]:
    """``(label, dx)`` over the layout: unit columns, Euler blocks replaced by 3 tangent directions."""
    labels = column_labels(asm.layout)
    out: list[tuple[str, np.ndarray]] = []
    for v in asm.layout.variables:
        jt = asm.mechanism.joint(v.joint).jtype if v.group != "coef" else None
        euler = jt.euler if (v.group == "q" and v.joint in asm.topology.tree_joints) else None
        for k in range(v.size):
            if euler is not None and euler.start <= k < euler.stop:
                continue
            dx = np.zeros(asm.layout.n)
            dx[v.start + k] = 1.0
            out.append((labels[v.start + k], dx))
        if euler is not None:
            p = np.asarray(coords[v.joint])[euler]
            assert abs(p @ p - 1.0) < 1e-12, "the random state must carry unit Euler parameters"
            for m, t in enumerate(euler_E(p)):  # rows of E(p): orthonormal, orthogonal to p
                dx = np.zeros(asm.layout.n)
                dx[v.start + euler.start : v.start + euler.stop] = t
                out.append((f"{v.key}[{euler.start}:{euler.stop}] tangent {m}", dx))
    return out


def junction_frame_residual(asm: Assembly, design, coords) -> np.ndarray:
    """The residual with every spherical row block resolved in its loop's junction frame."""
    Phi = asm.residual(design, coords)
    kin = asm.kinematics(design, coords)
    for b, A_p in spherical_blocks(asm, kin):
        Phi[b] = A_p.T @ Phi[b]
    return Phi


def spherical_blocks(asm: Assembly, kin) -> list[tuple[slice, np.ndarray]]:
    """``(rows, A_junction)`` of each spherical constraint's three rows."""
    loops = {lp.cut_joint: lp for lp in asm.topology.loops}
    out = []
    for blk in asm.row_blocks:
        if blk.kind != "cut":
            continue
        junction = loops[blk.joint].junction
        A_p = np.eye(3) if junction == WORLD else kin.A[junction]
        for k, lab in enumerate(blk.labels):
            if lab == "spherical[0]":
                out.append((slice(blk.rows.start + k, blk.rows.start + k + 3), A_p))
    return out


def fd_residual(asm: Assembly, design, coords, dx: np.ndarray, junction_frame: bool = False) -> np.ndarray:
    def res(state):
        return junction_frame_residual(asm, *state) if junction_frame else asm.residual(*state)

    plus = res(retract(asm.layout, design, coords, EPS * dx))
    minus = res(retract(asm.layout, design, coords, -EPS * dx))
    fd = (plus - minus) / (2 * EPS)
    if junction_frame:
        for b, A_p in spherical_blocks(asm, asm.kinematics(design, coords)):
            fd[b] = A_p @ fd[b]
    return fd


def check_jacobian(asm: Assembly, design, coords, junction_frame: bool = True) -> list[str]:
    """Labels of the columns where ``J`` and central differences disagree (empty if none)."""
    _, J = asm.evaluate(design, coords)
    scale = max(1.0, float(np.max(np.abs(J))))
    bad = []
    for label, dx in directions(asm, coords):
        fd, an = fd_residual(asm, design, coords, dx, junction_frame), J @ dx
        err = np.abs(fd - an)
        if np.any(err > RTOL * (scale + np.abs(fd))):
            row = int(np.argmax(err))
            bad.append(f"{label}: row {asm.row_labels[row]} analytic {an[row]:.9g} vs FD {fd[row]:.9g}")
    return bad


@pytest.mark.parametrize("rm", MECHANISMS, ids=IDS)
def test_jacobian_columns_against_central_differences(rm):
    asm = rm.assembly()
    bad = check_jacobian(asm, rm.design, rm.coordinates)
    assert not bad, f"{rm.describe()}\nwrong Jacobian columns:\n" + "\n".join(bad)


@pytest.mark.parametrize("rm", MECHANISMS[:6], ids=IDS[:6])
def test_jacobian_at_an_assembled_state(rm):
    """Where the cut constraints hold (d = 0), J is the derivative of the plain global residual."""
    am = random_mechanism(
        rm.seed,
        [j.type for j in rm.mechanism.joints if j.cut is False],
        [(rm.mechanism.joint(k).type, kind) for k, kind in rm.loop_kinds.items()],
        n_fixed=sum(b.fixed for b in rm.mechanism.bodies),
        assembled=True,
        couplings=len(rm.mechanism.couplings),
    )
    asm = am.assembly()
    Phi = asm.residual(am.design, am.coordinates)
    assert np.max(np.abs(Phi)) < 1e-12
    bad = check_jacobian(asm, am.design, am.coordinates, junction_frame=False)
    assert not bad, f"{am.describe()}\nwrong Jacobian columns:\n" + "\n".join(bad)


def test_normalisation_rows_are_exact_in_every_direction():
    """``p . p - 1`` has the true gradient ``2p`` (also along p, unlike the cut rows)."""
    rm = next(m for m in MECHANISMS if sum(b.kind == "euler" for b in m.assembly().row_blocks) >= 2)
    asm = rm.assembly()
    # off the unit sphere on purpose
    coords = as_coordinates({k: v * 1.1 for k, v in rm.coordinates.items()})
    _, J = asm.evaluate(rm.design, coords)
    blocks = [b for b in asm.row_blocks if b.kind == "euler"]
    labels = column_labels(asm.layout)
    for k in range(asm.layout.n):
        dx = np.zeros(asm.layout.n)
        dx[k] = 1.0
        fd = fd_residual(asm, rm.design, coords, dx)
        for b in blocks:
            assert np.allclose(fd[b.rows], J[b.rows, k], rtol=1e-7, atol=1e-8), (b.joint, labels[k])


# --- coverage of the generated suite ------------------------------------------------------------
def test_suite_covers_every_type_and_both_loop_cases():
    tree_fwd, tree_rev, cut_kinds, cases, junctions, fields = set(), set(), set(), set(), set(), set()
    for rm in MECHANISMS:
        asm = rm.assembly()
        fixed = {b.name for b in rm.mechanism.bodies if b.fixed}
        for t in asm.topology.tree:
            (tree_rev if t.reversed else tree_fwd).add(rm.mechanism.joint(t.joint).type)
            fields |= {(f, t.reversed) for f in rm.mechanism.joint(t.joint).fields}
        for lp in asm.topology.loops:
            kind = rm.loop_kinds[lp.cut_joint]
            cut_kinds.add((rm.mechanism.joint(lp.cut_joint).type, kind))
            cases.add(lp.case)
            assert lp.case == (1 if kind == "adjacent" else 2), (rm.seed, lp)
            junctions.add("world" if lp.junction == WORLD else "fixed" if lp.junction in fixed else "moving")
    assert tree_fwd == set(TREE_TYPES), set(TREE_TYPES) - tree_fwd
    assert tree_rev == set(TREE_TYPES), set(TREE_TYPES) - tree_rev
    missing = {(t, k) for t in CUT_TYPES for k in LOOP_KINDS} - cut_kinds
    assert not missing, missing
    assert fields == {(f, rev) for f in ("s_i", "s_j", "C_i", "C_j") for rev in (False, True)}
    assert cases == {1, 2}
    assert junctions == {"world", "fixed", "moving"}
    coupled = {
        (rm.mechanism.joint(c.joint_a).type, rm.mechanism.joint(c.joint_b).type, t.reversed)
        for rm in MECHANISMS
        for c in rm.mechanism.couplings
        for t in rm.assembly().topology.tree
        if t.joint == c.joint_a
    }
    assert {(a, b) for a, b, _ in coupled} == {
        (a, b) for a in ("revolute", "translational") for b in ("revolute", "translational")
    }
    assert {rev for _, _, rev in coupled} == {False, True}


# --- perturbations: retract does exactly the documented updates ---------------------------------
def test_retract_updates_as_documented():
    rm = MECHANISMS[1]
    asm = rm.assembly()
    rng = np.random.default_rng(7)
    dx = rng.normal(size=asm.layout.n) * 0.1
    design, coords = retract(asm.layout, rm.design, rm.coordinates, dx)
    for v in asm.layout.variables:
        step = dx[v.columns]
        if v.group == "q":
            assert np.allclose(coords[v.joint], rm.coordinates[v.joint] + step, rtol=0, atol=1e-15)
        elif v.group == "C":
            assert np.allclose(design[v.key], exp_so3(step) @ rm.design[v.key], rtol=0, atol=1e-15)
        else:
            assert np.allclose(
                design[v.key], rm.design[v.key] + (step if v.group == "s" else step[0]), rtol=0, atol=1e-15
            )


# --- loops across two fixed bodies ---------------------------------------------------------------
def test_loop_between_two_fixed_bodies_has_world_junction():
    """A loop whose chains end at two different fixed bodies (junction = the world node):
    the fixed bodies contribute no tree joints to the loop paths."""
    bodies = (
        Body("G0", fixed=True),
        Body("G1", fixed=True, position=(1.0, 0.0, 0.0)),
        Body("B1"),
        Body("B2"),
    )
    joints = (
        Joint("T1", "revolute", "G0", "B1", frozenset({"s_j"}), cut=False),
        Joint("T2", "revolute", "G1", "B2", frozenset({"s_j"}), cut=False),
        Joint("K1", "distance", "B1", "B2", frozenset({"s_i", "length"})),
    )
    mech = Mechanism(bodies, joints)
    design = Design(
        {"T1.s_j": [-0.3, 0.1, 0.0], "T2.s_j": [0.2, 0.4, 0.1], "K1.s_i": [0.1, 0.2, 0.3], "K1.length": 1.0}
    )
    coords = as_coordinates({"T1": [0.3], "T2": [-0.7]})
    asm = Assembly(mech)
    (lp,) = asm.topology.loops
    assert (lp.junction, lp.case, lp.path_i, lp.path_j) == (WORLD, 2, ("T1",), ("T2",))
    assert not check_jacobian(asm, design, coords, junction_frame=False)  # world: a fixed frame


# --- B, M, N twists on the body poses ------------------------------------------------------------
def subtree(topo, joint: str) -> set[str]:
    child = next(t.child for t in topo.tree if t.joint == joint)
    below, grew = {child}, True
    while grew:
        grew = False
        for t in topo.tree:
            if t.parent in below and t.child not in below:
                below.add(t.child)
                grew = True
    return below


def pose_twist(kin_p, kin_m, kin0, body: str) -> np.ndarray:
    dr = (kin_p.r[body] - kin_m.r[body]) / (2 * EPS)
    W = (kin_p.A[body] - kin_m.A[body]) / (2 * EPS) @ kin0.A[body].T
    W = 0.5 * (W - W.T)
    dpi = np.array([W[2, 1], W[0, 2], W[1, 0]])
    return np.concatenate([dr + tilde(kin0.r[body]) @ dpi, dpi])


@pytest.mark.parametrize("rm", MECHANISMS[::2], ids=IDS[::2])
def test_tree_joint_twists_move_the_subtree(rm):
    asm = rm.assembly()
    mech, topo, layout = asm.mechanism, asm.topology, asm.layout
    design, coords = rm.design, rm.coordinates
    kin0 = forward_kinematics(mech, topo, design, coords)
    twists = tree_joint_twists(mech, topo, layout, kin0, coords)
    dirs = dict(directions(asm, coords))
    labels = column_labels(layout)
    bad = []
    for t in topo.tree:
        below = subtree(topo, t.joint)
        for cols, T in twists[t.joint]:
            assert T.shape == (6, cols.stop - cols.start)
            for label, dx in dirs.items():
                if not np.any(dx[cols]) or np.any(np.delete(dx, np.arange(cols.start, cols.stop))):
                    continue
                kp = forward_kinematics(mech, topo, *retract(layout, design, coords, EPS * dx))
                km = forward_kinematics(mech, topo, *retract(layout, design, coords, -EPS * dx))
                expected = T @ dx[cols]
                for b in topo.order:
                    fd = pose_twist(kp, km, kin0, b)
                    want = expected if b in below else np.zeros(6)
                    if not np.allclose(fd, want, rtol=RTOL, atol=RTOL * max(1.0, np.max(np.abs(T)))):
                        bad.append(f"{label} (joint {t.joint}) body {b}: twist {want} vs FD {fd}")
        # every layout variable of the joint has a twist block
        keys = {v.key for v in layout.variables if v.joint == t.joint}
        covered = {labels[c.start].split("[")[0] for c, _ in twists[t.joint]}
        assert keys == covered, (t.joint, keys, covered)
    assert not bad, f"{rm.describe()}\n" + "\n".join(bad)


def test_spherical_rows_are_resolved_in_the_junction_frame():
    """Away from assembly, a tree joint above a moving junction rotates the gap d of a spherical
    row (FD of the global residual: e_z x d for a revolute about global z) but has a zero
    column in J: the paper's eq. (48) drops it, so J is the derivative of A_p^T d, rotated back."""
    bodies = (Body("G0", fixed=True), Body("B1"), Body("B2"))
    joints = (
        Joint("T1", "revolute", "G0", "B1", frozenset({"s_j"}), cut=False),
        Joint("T2", "revolute", "B1", "B2", frozenset({"s_i"}), cut=False),
        Joint("K1", "spherical-point", "B1", "B2", frozenset({"s_i", "s_j"})),
    )
    design = Design(
        {"T1.s_j": [0.1, 0.0, 0.2], "T2.s_i": [1.0, 0.0, 0.0], "K1.s_i": [0.5, 0.5, 0.0], "K1.s_j": [0.0, 0.3, 0.1]}
    )
    coords = as_coordinates({"T1": [0.4], "T2": [0.9]})
    asm = Assembly(Mechanism(bodies, joints))
    (lp,) = asm.topology.loops
    assert (lp.junction, lp.case, lp.path_i, lp.path_j) == ("B1", 1, (), ("T2",))
    d, J = asm.evaluate(design, coords)  # the three spherical rows are d itself
    dx = np.zeros(asm.layout.n)
    dx[asm.layout["T1.q"].start] = 1.0
    np.testing.assert_allclose(fd_residual(asm, design, coords, dx), np.cross([0.0, 0.0, 1.0], d), atol=1e-8)
    np.testing.assert_allclose(J @ dx, 0.0, atol=1e-15)
    assert not check_jacobian(asm, design, coords, junction_frame=True)
    bad = check_jacobian(asm, design, coords, junction_frame=False)
    assert bad and all(b.startswith(("T1.", "G0")) for b in bad), bad
