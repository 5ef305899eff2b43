"""Joint types: tree-form motion against the placement, cut forms against the tree forms.

Tree form: ``motion(q) = (dd''/dq, H'')`` must be the derivative of ``placement(q) = (A'', d'')``
on the manifold, all in joint frame i: ``dd'' = dd''/dq dq`` and ``dA'' = tilde(H'' dq) A''``.
For Euler-parameter joints this holds only along tangent directions ``dp`` with ``p . dp = 0``
at unit ``p`` (the paper's ``H = 2E(p)`` is exact there; along ``p`` itself ``A(p)`` scales).

Cut form: with joint frame j placed by the type's own tree form at random q, every cut
constraint is satisfied; the cut form has the documented number of rows, its rows are
independent, and together with the tree form's motion they span the six relative freedoms
(rows + degrees of freedom = 6, and the tree motion is in the null space of the cut rows).
"""

from __future__ import annotations

import re
import sys

import numpy as np
import pytest

from kinprop.constraints import Spherical as SphericalConstraint
from kinprop.joints import REGISTRY, joint_type
from kinprop.spatial import EZ, euler_E, is_rotation, tilde
from random_mechanisms import CUT_TYPES, TREE_TYPES, assembled_cut_placement, random_coordinates, random_rotation

EPS = 1e-6
SEEDS = range(5)

#: rows of each cut form (6 minus the relative freedoms it leaves)
CUT_ROWS = {
    "revolute": 5,
    "translational": 5,
    "cylindrical": 4,
    "universal": 4,
    "spherical": 3,
    "fixed": 6,
    "spherical-translational": 2,
    "revolute-spherical": 2,
    "translational-distance": 1,
    "dot-1": 1,
    "dot-2": 1,
    "spherical-point": 3,
    "distance": 1,
}


def test_registry_matches_the_generator_lists():
    assert {n for n, jt in REGISTRY.items() if jt.tree} == set(TREE_TYPES)
    assert {n for n, jt in REGISTRY.items() if jt.cut} == set(CUT_TYPES) == set(CUT_ROWS)


def tangent_directions(jt, q) -> list[tuple[str, np.ndarray]]:
    """Unit coordinate directions, the Euler block replaced by the three rows of E(p)."""
    out = []
    for k in range(jt.n_coordinates):
        if jt.euler is not None and jt.euler.start <= k < jt.euler.stop:
            continue
        e = np.zeros(jt.n_coordinates)
        e[k] = 1.0
        out.append((f"q[{k}]", e))
    if jt.euler is not None:
        p = q[jt.euler]
        assert abs(p @ p - 1) < 1e-14
        for m, t in enumerate(euler_E(p)):
            assert abs(t @ p) < 1e-14
            e = np.zeros(jt.n_coordinates)
            e[jt.euler] = t
            out.append((f"p tangent {m}", e))
    return out


def vee(W):
    W = 0.5 * (W - W.T)
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("name", TREE_TYPES)
def test_motion_is_the_derivative_of_the_placement(name, seed):
    jt = joint_type(name)
    rng = np.random.default_rng(10 * seed + 1)
    q = random_coordinates(name, rng)
    A, d = jt.placement(q)
    assert is_rotation(A, tol=1e-12) and d.shape == (3,)
    dd, H = jt.motion(q)
    assert dd.shape == H.shape == (3, jt.n_coordinates)
    for label, e in tangent_directions(jt, q):
        Ap, dp = jt.placement(q + EPS * e)
        Am, dm = jt.placement(q - EPS * e)
        fd_d = (dp - dm) / (2 * EPS)
        dA = (Ap - Am) / (2 * EPS)
        fd_w = vee(dA @ A.T)
        np.testing.assert_allclose(dd @ e, fd_d, rtol=1e-7, atol=1e-8, err_msg=f"{name} dd''/dq along {label}")
        np.testing.assert_allclose(H @ e, fd_w, rtol=1e-7, atol=1e-8, err_msg=f"{name} H'' along {label}")
        # the derivative of A'' is exactly a rotation rate (dA A^T skew) along these directions
        np.testing.assert_allclose(dA @ A.T + (dA @ A.T).T, 0, atol=1e-8, err_msg=f"{name} along {label}")


@pytest.mark.parametrize("name", [n for n in TREE_TYPES if joint_type(n).euler is not None])
def test_euler_map_ignores_the_radial_direction(name):
    """``H = 2E(p)`` annihilates p (E(p) p = 0): the radial direction is left to the
    normalisation row ``p . p - 1``."""
    jt = joint_type(name)
    q = random_coordinates(name, np.random.default_rng(3))
    dd, H = jt.motion(q)
    radial = np.zeros(jt.n_coordinates)
    radial[jt.euler] = q[jt.euler]
    np.testing.assert_allclose(H @ radial, 0, atol=1e-15)
    np.testing.assert_allclose(dd @ radial, 0, atol=1e-15)


def test_free_joint_motion_is_exact_off_the_unit_sphere():
    """The free joint (not one of the paper's) turns its body by the normalised ``p``: its
    placement is a rotation at every iterate and ``H = 2E(p)/(p.p)`` is the derivative in every
    direction, along ``p`` too (the Stewart solve converges quadratically, no polishing step).
    The paper's spherical and S-T joints keep ``E(p) G(p)^T`` (PAPER-NOTES: the tables need it)."""
    jt = joint_type("free")
    rng = np.random.default_rng(7)
    q = random_coordinates("free", rng)
    q[jt.euler] *= 1.05  # off the unit sphere, as after a Newton step
    A, _ = jt.placement(q)
    assert is_rotation(A, tol=1e-12)
    dd, H = jt.motion(q)
    for k in range(jt.n_coordinates):
        e = np.zeros(jt.n_coordinates)
        e[k] = 1.0
        (Ap, dp), (Am, dm) = jt.placement(q + EPS * e), jt.placement(q - EPS * e)
        np.testing.assert_allclose(dd @ e, (dp - dm) / (2 * EPS), atol=1e-8, err_msg=f"dd''/dq[{k}]")
        dA = (Ap - Am) / (2 * EPS)
        np.testing.assert_allclose(dA @ A.T, tilde(H @ e), atol=1e-8, err_msg=f"H'' q[{k}]")
    sph, p = joint_type("spherical"), q[jt.euler]
    assert not is_rotation(sph.placement(p)[0], tol=1e-3)  # the paper's E G^T scales by p.p


def test_default_coordinates_are_the_identity_placement():
    for name in TREE_TYPES:
        jt = joint_type(name)
        A, d = jt.placement(jt.default_coordinates())
        np.testing.assert_allclose(A, np.eye(3), atol=1e-15, err_msg=name)
        np.testing.assert_allclose(d, 0, atol=1e-15, err_msg=name)


# --- cut forms ---------------------------------------------------------------------------------
def cut_values(jt, P_i, R_i, P_j, R_j, length=0.0, qc=None):
    """Residual of the cut form and its partials w.r.t. frame j's point and global rotation."""
    qc = jt.default_cut_coordinates() if qc is None else qc
    u, _ = jt.cut_offset(qc)
    d = P_j - (P_i + R_i @ u)
    vals, Pd, Wj = [], [], []
    for c in jt.constraints():
        bv = c.evaluate(d, R_i, R_j, length)
        vals.append(bv.value), Pd.append(bv.Phi_d), Wj.append(bv.Phi_wj)
    return np.concatenate(vals), np.vstack(Pd), np.vstack(Wj)


@pytest.mark.parametrize("name", CUT_TYPES)
def test_cut_form_has_the_documented_rows(name):
    jt = joint_type(name)
    assert jt.n_constraints == CUT_ROWS[name]
    assert sum(c.rows for c in jt.constraints()) == CUT_ROWS[name]
    doc = sys.modules[type(jt).__module__].__doc__ or ""
    m = re.search(r"\((\d) constraints when cut\)", doc)
    if m:  # the module docstring states the count
        assert int(m.group(1)) == CUT_ROWS[name]


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("name", [n for n in CUT_TYPES if joint_type(n).tree])
def test_cut_form_holds_on_the_tree_form(name, seed):
    """Frame j placed by the type's tree form satisfies its cut constraints (to 1e-12); the
    rows are independent, annihilate the tree motion, and rows + freedoms = 6."""
    jt = joint_type(name)
    rng = np.random.default_rng(50 + seed)
    P_i, R_i = rng.normal(size=3), random_rotation(rng)
    q = random_coordinates(name, rng)
    A, dpp = jt.placement(q)
    P_j, R_j = P_i + R_i @ dpp, R_i @ A
    value, Phi_P, Phi_w = cut_values(jt, P_i, R_i, P_j, R_j)
    assert value.shape == (CUT_ROWS[name],)
    np.testing.assert_allclose(value, 0, atol=1e-12, err_msg=name)

    # motion of frame j in the cut rows' variables: dP_j = R_i dd'' dq, w_j = R_i H'' dq
    dd, H = jt.motion(q)
    S = np.vstack([R_i @ dd, R_i @ H])
    if jt.euler is not None:
        T = np.eye(jt.n_coordinates)
        S = S @ np.hstack(
            [np.delete(T, np.arange(jt.euler.start, jt.euler.stop), axis=1), T[:, jt.euler] @ euler_E(q[jt.euler]).T]
        )
    Jc = np.hstack([Phi_P, Phi_w])
    dof = int(np.linalg.matrix_rank(S, tol=1e-9)) if S.size else 0
    assert np.linalg.matrix_rank(Jc, tol=1e-9) == CUT_ROWS[name], f"{name}: dependent cut rows"
    assert dof + CUT_ROWS[name] == 6, f"{name}: {dof} freedoms + {CUT_ROWS[name]} rows"
    np.testing.assert_allclose(Jc @ S, 0, atol=1e-12, err_msg=f"{name}: tree motion violates the cut rows")


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("name", [n for n in CUT_TYPES if not joint_type(n).tree])
def test_cut_only_forms_hold_where_placed(name, seed):
    """Cut-only types: a placement built to satisfy them does, to 1e-12, and a generic one does not."""
    jt = joint_type(name)
    rng = np.random.default_rng(70 + seed)
    P_i, R_i = rng.normal(size=3), random_rotation(rng)
    qc = rng.uniform(-1, 1, size=jt.n_cut_coordinates)
    A, dpp, length = assembled_cut_placement(name, rng, qc)
    P_j, R_j = P_i + R_i @ dpp, R_i @ A
    value, _, _ = cut_values(jt, P_i, R_i, P_j, R_j, length, qc)
    assert value.shape == (CUT_ROWS[name],)
    np.testing.assert_allclose(value, 0, atol=1e-12, err_msg=name)
    generic, _, _ = cut_values(jt, P_i, R_i, P_j + rng.normal(size=3), random_rotation(rng) @ R_j, length, qc)
    assert np.max(np.abs(generic)) > 1e-6


def test_free_joint_is_tree_only():
    jt = joint_type("free")
    assert jt.tree and not jt.cut
    with pytest.raises(NotImplementedError):
        jt.constraints()


# --- the T-D joint's own coordinate --------------------------------------------------------------
def test_translational_distance_own_coordinate():
    """T-D (eqs. 53-57): the rack slides the point on body i by ``q3`` along ``z''_i``; ``du/dq3``
    matches central differences and the distance row is ``|P_j - P_i - R_i e_z q3|^2 - l^2``."""
    jt = joint_type("translational-distance")
    assert (jt.n_cut_coordinates, jt.has_length, jt.tree, jt.n_coordinates) == (1, True, False, 0)
    np.testing.assert_array_equal(jt.default_cut_coordinates(), [0.0])
    rng = np.random.default_rng(11)
    for qc in (np.array([0.0]), np.array([0.37]), np.array([-1.3])):
        u, du = jt.cut_offset(qc)
        assert du.shape == (3, 1)
        np.testing.assert_allclose(u, EZ * qc[0], atol=1e-15)
        fd = (jt.cut_offset(qc + EPS)[0] - jt.cut_offset(qc - EPS)[0]) / (2 * EPS)
        np.testing.assert_allclose(du[:, 0], fd, atol=1e-9)
        P_i, R_i, P_j, R_j, length = (
            rng.normal(size=3),
            random_rotation(rng),
            rng.normal(size=3),
            random_rotation(rng),
            0.8,
        )
        value, Phi_P, _ = cut_values(jt, P_i, R_i, P_j, R_j, length, qc)
        g = P_j - P_i - R_i @ EZ * qc[0]
        np.testing.assert_allclose(value, [g @ g - length**2], rtol=1e-13)
        # own-coordinate column: dPhi/dq3 = -Phi_P R_i du (the slider moves the point on body i)
        vp, _, _ = cut_values(jt, P_i, R_i, P_j, R_j, length, qc + EPS)
        vm, _, _ = cut_values(jt, P_i, R_i, P_j, R_j, length, qc - EPS)
        np.testing.assert_allclose(-Phi_P @ R_i @ du, ((vp - vm) / (2 * EPS))[:, None], rtol=1e-7, atol=1e-8)


def test_spherical_cut_form_is_the_basic_spherical():
    assert joint_type("spherical").constraints() == (SphericalConstraint(),)
