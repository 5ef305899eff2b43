"""The four basic constraints (dot-1, dot-2 on i and on j, spherical, distance) and their partials.

Two levels are checked, each against central differences and the body level also against the
closed forms of the paper's Table 1:

* joint-frame level: ``BasicConstraint.evaluate(d, R_i, R_j, l)`` gives ``Phi_d``, ``Phi_wi``,
  ``Phi_wj``, ``Phi_l``; ``w_i``, ``w_j`` are virtual rotations of the joint frames in the GLOBAL
  frame (``R <- exp(tilde(w)) R``).
* body level (Table 1): ``Phi(r_i, A_i, s'_ij, C_ij, r_j, A_j, s'_ji, C_ji, l)`` with
  ``d_ij = r_j + A_j s'_ji - r_i - A_i s'_ij`` and ``R_i = A_i C_ij``, ``R_j = A_j C_ji``. The
  chain rule is the one of ``kinprop.kinematics.kernels``: ``Phi_r_i = -Phi_d``,
  ``Phi_r_j = Phi_d``, ``Phi_pi_i = Phi_d tilde(s_ij) + Phi_wi``, ``Phi_pi_j = -Phi_d tilde(s_ji)
  + Phi_wj``, ``Phi_s'_ij = -Phi_d A_i``, ``Phi_s'_ji = Phi_d A_j``, ``Phi_xi_ij = Phi_wi``,
  ``Phi_xi_ji = Phi_wj``, where ``s_ij = A_i s'_ij`` is global.

Frames. ``pi`` is the global virtual rotation of a body (``A <- exp(tilde(dpi)) A``). Table 1's
xi columns are w.r.t. the GLOBAL rotation of the joint frame (``A C <- exp(tilde(dxi)) A C``,
i.e. ``C <- A^T exp(tilde(dxi)) A C``), which is what the table's entries (equal to the pi
entries for dot-1) encode. kinprop's design variable ``xi'`` is in the BODY frame
(``C <- exp(tilde(xi')) C``, PAPER-NOTES), so its column is ``Phi_xi A`` — checked here too.
Dot-2 with the axis on body j is not in Table 1; its closed form is the mirror image of the
dot-2 row (derived the same way, eqs. 8-14 with i and j swapped in the axis).
"""

from __future__ import annotations

import numpy as np
import pytest

from kinprop.constraints import Distance, Dot1, Dot2, Spherical
from kinprop.spatial import EX, EY, EZ, exp_so3, tilde

EPS = 1e-6
KINDS = ("dot-1", "dot-2-i", "dot-2-j", "spherical", "distance")
SEEDS = range(6)


def unit(rng):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def rotation(rng):
    return exp_so3(unit(rng) * rng.uniform(0.1, np.pi - 0.1))


def make(kind: str, rng):
    """A constraint of ``kind`` with random joint-frame axes (the first seed uses the defaults)."""
    axes = (EZ, EZ) if rng.random() < 0.2 else (unit(rng), unit(rng))
    return {
        "dot-1": lambda: Dot1(*axes),
        "dot-2-i": lambda: Dot2(axes[0], on="i"),
        "dot-2-j": lambda: Dot2(axes[1], on="j"),
        "spherical": Spherical,
        "distance": Distance,
    }[kind]()


def rows(c) -> int:
    return type(c).rows


# --- joint-frame level -----------------------------------------------------------------------
@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("kind", KINDS)
def test_joint_frame_partials_against_central_differences(kind, seed):
    rng = np.random.default_rng(100 + seed)
    c = make(kind, rng)
    d, R_i, R_j, l = rng.normal(size=3), rotation(rng), rotation(rng), rng.uniform(0.5, 2.0)
    bv = c.evaluate(d, R_i, R_j, l)
    m = rows(c)
    assert bv.value.shape == (m,) and bv.Phi_l.shape == (m,)
    assert bv.Phi_d.shape == bv.Phi_wi.shape == bv.Phi_wj.shape == (m, 3)

    def val(d=d, R_i=R_i, R_j=R_j, l=l):
        return c.evaluate(d, R_i, R_j, l).value

    for k, e in enumerate(np.eye(3)):
        fd_d = (val(d=d + EPS * e) - val(d=d - EPS * e)) / (2 * EPS)
        fd_wi = (val(R_i=exp_so3(EPS * e) @ R_i) - val(R_i=exp_so3(-EPS * e) @ R_i)) / (2 * EPS)
        fd_wj = (val(R_j=exp_so3(EPS * e) @ R_j) - val(R_j=exp_so3(-EPS * e) @ R_j)) / (2 * EPS)
        np.testing.assert_allclose(bv.Phi_d[:, k], fd_d, rtol=1e-7, atol=1e-8, err_msg=f"{kind} Phi_d[:, {k}]")
        np.testing.assert_allclose(bv.Phi_wi[:, k], fd_wi, rtol=1e-7, atol=1e-8, err_msg=f"{kind} Phi_wi[:, {k}]")
        np.testing.assert_allclose(bv.Phi_wj[:, k], fd_wj, rtol=1e-7, atol=1e-8, err_msg=f"{kind} Phi_wj[:, {k}]")
    fd_l = (val(l=l + EPS) - val(l=l - EPS)) / (2 * EPS)
    np.testing.assert_allclose(bv.Phi_l, fd_l, rtol=1e-7, atol=1e-8, err_msg=f"{kind} Phi_l")


# --- body level: Table 1 ---------------------------------------------------------------------
class BodyPair:
    """Random poses of bodies i and j, joint frames on both, and a length."""

    def __init__(self, rng):
        self.r_i, self.A_i, self.s_i, self.C_i = rng.normal(size=3), rotation(rng), rng.normal(size=3), rotation(rng)
        self.r_j, self.A_j, self.s_j, self.C_j = rng.normal(size=3), rotation(rng), rng.normal(size=3), rotation(rng)
        self.l = rng.uniform(0.5, 2.0)

    def value(self, c, **changes):
        v = {**vars(self), **changes}
        d = v["r_j"] + v["A_j"] @ v["s_j"] - v["r_i"] - v["A_i"] @ v["s_i"]
        return c.evaluate(d, v["A_i"] @ v["C_i"], v["A_j"] @ v["C_j"], v["l"]).value

    @property
    def d(self):
        return self.r_j + self.A_j @ self.s_j - self.r_i - self.A_i @ self.s_i


def table1(kind: str, c, p: BodyPair) -> dict[str, np.ndarray]:
    """Closed forms of Table 1 (rows: Phi_r_i, Phi_r_j, Phi_pi_i, Phi_pi_j, Phi_s'_ij, Phi_s'_ji,
    Phi_xi_ij, Phi_xi_ji; xi global), as (m, 3) arrays."""
    d, A_i, A_j = p.d, p.A_i, p.A_j
    s_ij, s_ji = A_i @ p.s_i, A_j @ p.s_j  # global joint position vectors (eq. 11)
    Z = np.zeros((1, 3))
    if kind == "dot-1":
        a_i, a_j = A_i @ p.C_i @ c.a_i, A_j @ p.C_j @ c.a_j
        return {
            "r_i": Z, "r_j": Z,
            "pi_i": -a_j @ tilde(a_i), "pi_j": -a_i @ tilde(a_j),
            "s_ij": Z, "s_ji": Z,
            "xi_ij": -a_j @ tilde(a_i), "xi_ji": -a_i @ tilde(a_j),
        }  # fmt: skip
    if kind == "dot-2-i":
        a_i = A_i @ p.C_i @ c.a
        return {
            "r_i": -a_i, "r_j": a_i,
            "pi_i": a_i @ tilde(s_ij) - d @ tilde(a_i), "pi_j": -a_i @ tilde(s_ji),
            "s_ij": -a_i @ A_i, "s_ji": a_i @ A_j,
            "xi_ij": -d @ tilde(a_i), "xi_ji": Z,
        }  # fmt: skip
    if kind == "dot-2-j":  # mirror image of the dot-2 row (not printed in Table 1)
        a_j = A_j @ p.C_j @ c.a
        return {
            "r_i": -a_j, "r_j": a_j,
            "pi_i": a_j @ tilde(s_ij), "pi_j": -a_j @ tilde(s_ji) - d @ tilde(a_j),
            "s_ij": -a_j @ A_i, "s_ji": a_j @ A_j,
            "xi_ij": Z, "xi_ji": -d @ tilde(a_j),
        }  # fmt: skip
    if kind == "spherical":
        Z3 = np.zeros((3, 3))
        return {
            "r_i": -np.eye(3), "r_j": np.eye(3),
            "pi_i": tilde(s_ij), "pi_j": -tilde(s_ji),
            "s_ij": -A_i, "s_ji": A_j,
            "xi_ij": Z3, "xi_ji": Z3,
        }  # fmt: skip
    if kind == "distance":
        return {
            "r_i": -2 * d, "r_j": 2 * d,
            "pi_i": 2 * d @ tilde(s_ij), "pi_j": -2 * d @ tilde(s_ji),
            "s_ij": -2 * d @ A_i, "s_ji": 2 * d @ A_j,
            "xi_ij": Z, "xi_ji": Z,
        }  # fmt: skip
    raise ValueError(kind)


def chain_rule(c, p: BodyPair) -> dict[str, np.ndarray]:
    """Body-level partials from the joint-frame ones, as kinematics/assembly.py composes them."""
    bv = c.evaluate(p.d, p.A_i @ p.C_i, p.A_j @ p.C_j, p.l)
    s_ij, s_ji = p.A_i @ p.s_i, p.A_j @ p.s_j
    return {
        "r_i": -bv.Phi_d,
        "r_j": bv.Phi_d,
        "pi_i": bv.Phi_d @ tilde(s_ij) + bv.Phi_wi,
        "pi_j": -bv.Phi_d @ tilde(s_ji) + bv.Phi_wj,
        "s_ij": -bv.Phi_d @ p.A_i,
        "s_ji": bv.Phi_d @ p.A_j,
        "xi_ij": bv.Phi_wi,
        "xi_ji": bv.Phi_wj,
    }


def perturbed(p: BodyPair, column: str, h: np.ndarray) -> dict[str, np.ndarray]:
    """The body-level change that the column's variable makes (see the module docstring)."""
    if column == "r_i":
        return {"r_i": p.r_i + h}
    if column == "r_j":
        return {"r_j": p.r_j + h}
    if column == "pi_i":
        return {"A_i": exp_so3(h) @ p.A_i}
    if column == "pi_j":
        return {"A_j": exp_so3(h) @ p.A_j}
    if column == "s_ij":
        return {"s_i": p.s_i + h}
    if column == "s_ji":
        return {"s_j": p.s_j + h}
    if column == "xi_ij":  # global rotation of joint frame i
        return {"C_i": p.A_i.T @ exp_so3(h) @ p.A_i @ p.C_i}
    if column == "xi_ji":
        return {"C_j": p.A_j.T @ exp_so3(h) @ p.A_j @ p.C_j}
    if column == "xi'_ij":  # body-frame rotation (kinprop's design variable)
        return {"C_i": exp_so3(h) @ p.C_i}
    if column == "xi'_ji":
        return {"C_j": exp_so3(h) @ p.C_j}
    raise ValueError(column)


def fd_block(c, p: BodyPair, column: str) -> np.ndarray:
    cols = []
    for e in np.eye(3):
        plus = p.value(c, **perturbed(p, column, EPS * e))
        minus = p.value(c, **perturbed(p, column, -EPS * e))
        cols.append((plus - minus) / (2 * EPS))
    return np.array(cols).T


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("kind", KINDS)
def test_table1_closed_forms(kind, seed):
    """Chain rule of the library == Table 1 == central differences, column by column."""
    rng = np.random.default_rng(200 + seed)
    c, p = make(kind, rng), BodyPair(rng)
    closed = {k: np.atleast_2d(v) for k, v in table1(kind, c, p).items()}
    ours = chain_rule(c, p)
    for col, T in closed.items():
        assert T.shape == (rows(c), 3)
        np.testing.assert_allclose(ours[col], T, rtol=1e-12, atol=1e-12, err_msg=f"{kind}: chain rule vs Table 1 {col}")
        np.testing.assert_allclose(fd_block(c, p, col), T, rtol=1e-7, atol=1e-7, err_msg=f"{kind}: FD vs Table 1 {col}")


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("kind", KINDS)
def test_body_frame_orientation_columns(kind, seed):
    """kinprop's xi' is in the body frame: its column is Table 1's (global) xi column times A."""
    rng = np.random.default_rng(300 + seed)
    c, p = make(kind, rng), BodyPair(rng)
    closed = {k: np.atleast_2d(v) for k, v in table1(kind, c, p).items()}
    for col, A in (("xi'_ij", p.A_i), ("xi'_ji", p.A_j)):
        glob = closed[col.replace("'", "")]
        np.testing.assert_allclose(fd_block(c, p, col), glob @ A, rtol=1e-7, atol=1e-7, err_msg=f"{kind} {col}")


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("kind", KINDS)
def test_values_and_length_partial(kind, seed):
    """The values are eqs. (1), (8), (15), (17); only the distance depends on l: -2 l."""
    rng = np.random.default_rng(400 + seed)
    c, p = make(kind, rng), BodyPair(rng)
    d, R_i, R_j = p.d, p.A_i @ p.C_i, p.A_j @ p.C_j
    bv = c.evaluate(d, R_i, R_j, p.l)
    expected = {
        "dot-1": lambda: [(R_i @ c.a_i) @ (R_j @ c.a_j)],
        "dot-2-i": lambda: [(R_i @ c.a) @ d],
        "dot-2-j": lambda: [(R_j @ c.a) @ d],
        "spherical": lambda: d,
        "distance": lambda: [d @ d - p.l**2],
    }[kind]()
    np.testing.assert_allclose(bv.value, expected, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(bv.Phi_l, [-2 * p.l] if kind == "distance" else np.zeros(rows(c)), rtol=1e-14)


def test_default_axes_are_the_paper_ones():
    """Defaults: dot-1 between z''_i and z''_j, dot-2 along z''_i (eqs. 1, 8)."""
    assert np.array_equal(Dot1().a_i, EZ) and np.array_equal(Dot1().a_j, EZ)
    assert np.array_equal(Dot2().a, EZ) and Dot2().on == "i"
    # the axes enter as given: x''_i . y''_j for identical frames is 0, z''.z'' is 1
    R = rotation(np.random.default_rng(5))
    assert abs(Dot1(EX, EY).evaluate(np.zeros(3), R, R, 0.0).value[0]) < 1e-15
    assert abs(Dot1().evaluate(np.zeros(3), R, R, 0.0).value[0] - 1.0) < 1e-15
