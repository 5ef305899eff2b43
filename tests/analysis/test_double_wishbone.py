"""examples/double_wishbone.yaml: mobility, camber/toe curves against an independent closed
construction, the design change, and the before/after figure."""

from __future__ import annotations

import math

import numpy as np
import pytest
from analysis_helpers import EXAMPLES
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from kinprop import propagate
from kinprop.analysis.metrics import camber_toe
from kinprop.analysis.mobility import mobility
from kinprop.analysis.sweep import sweep

pytestmark = pytest.mark.filterwarnings("ignore::kinprop.SingularityWarning")

# published hardpoints (Project Chrono HMMWV front, inches -> mm), as in the example's header
HP = {
    k: np.array(v) * 25.4
    for k, v in {
        "LCA_F": (8.79, 12.09, 0.0),
        "LCA_B": (-8.79, 12.09, 0.0),
        "LCA_U": (-1.40, 30.965, -4.65),
        "UCA_F": (-1.8864, 17.5575, 9.6308),
        "UCA_B": (-10.5596, 18.8085, 7.6992),
        "UCA_U": (-2.088, 28.17, 8.484),
        "TIEROD_C": (-9.855, 17.655, 2.135),
        "TIEROD_U": (-6.922, 32.327, -0.643),
        "SPINDLE": (-1.59, 35.815, -1.035),
    }.items()
}


def rotate(p, origin, axis, angle):
    return origin + Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).apply(p - origin)


def closed_camber_toe(theta: float) -> tuple[float, float, float]:
    """Independent construction: lower arm angle -> (wheel travel, camber, toe), by two 1-D roots."""
    lbj = rotate(HP["LCA_U"], HP["LCA_B"], HP["LCA_F"] - HP["LCA_B"], theta)
    r_kp = np.linalg.norm(HP["UCA_U"] - HP["LCA_U"])
    uca_axis = HP["UCA_F"] - HP["UCA_B"]
    phi = brentq(lambda a: np.linalg.norm(rotate(HP["UCA_U"], HP["UCA_B"], uca_axis, a) - lbj) - r_kp, -0.6, 0.6)
    ubj = rotate(HP["UCA_U"], HP["UCA_B"], uca_axis, phi)
    # upright: the rotation taking the design kingpin onto the new one, then a steer about it
    k0, k1 = HP["UCA_U"] - HP["LCA_U"], ubj - lbj
    R0 = Rotation.align_vectors([k1], [k0])[0]
    l_tr = np.linalg.norm(HP["TIEROD_U"] - HP["TIEROD_C"])

    def pose(psi):
        return Rotation.from_rotvec(psi * k1 / np.linalg.norm(k1)) * R0

    def tie_rod(psi):
        return np.linalg.norm(lbj + pose(psi).apply(HP["TIEROD_U"] - HP["LCA_U"]) - HP["TIEROD_C"]) - l_tr

    psi = brentq(tie_rod, -0.5, 0.5)
    R = pose(psi)
    centre = lbj + R.apply(HP["SPINDLE"] - HP["LCA_U"])
    camber, toe = camber_toe(R.apply([0.0, 1.0, 0.0]))
    return centre[2] - HP["SPINDLE"][2], camber, toe


def test_mobility_one_with_the_rack_fixed(double_wishbone):
    rep = mobility(double_wishbone)
    assert rep.mobility == 1 and rep.gruebler == 1 and not rep.redundant


def test_camber_toe_curves_match_closed_construction(double_wishbone):
    df = sweep(double_wishbone, ["LCA=-6.3:6.3:8"], outputs=["wheel_centre_dz", "camber", "toe"], tol=1e-9).frame
    assert (df["status"] == "converged").all()
    assert df["wheel_centre_dz"].min() < -50 and df["wheel_centre_dz"].max() > 50  # +-50 mm covered
    for _, row in df.iterrows():
        dz, camber, toe = closed_camber_toe(math.radians(row["LCA.q"]))
        assert row["wheel_centre_dz"] == pytest.approx(dz, abs=1e-6)
        assert row["camber"] == pytest.approx(camber, abs=1e-7)
        assert row["toe"] == pytest.approx(toe, abs=1e-7)
    # this geometry gains negative camber and toe-out in bump
    assert np.all(np.diff(df["camber"]) < 0) and np.all(np.diff(df["toe"]) < 0)


def test_design_change_moves_the_curves_and_the_figure(double_wishbone, tmp_path):
    from kinprop.plot.curves import plot_curves

    s = np.array(double_wishbone.design["UCA.s_i"])
    s[2] += 10.0
    prop = propagate(double_wishbone, {"UCA.s_i": s}, ("q",), tol=1e-9)
    assert prop.converged, prop.result.message
    names = ["wheel_centre_dz", "camber", "toe"]
    before = sweep(double_wishbone, ["LCA=-6:6:6"], outputs=names, tol=1e-9).frame
    after = sweep(prop.after, ["LCA=-6:6:6"], outputs=names, tol=1e-9).frame
    assert (after["status"] == "converged").all()
    gain_before = np.polyfit(before["wheel_centre_dz"], before["camber"], 1)[0]
    gain_after = np.polyfit(after["wheel_centre_dz"], after["camber"], 1)[0]
    assert abs(gain_after - gain_before) > 1e-3  # deg/mm: the curve changed shape, not only offset
    out = tmp_path / "curves.png"
    curves = {"before": before, "after": after}
    fig = plot_curves(curves, "wheel_centre_dz", ["camber", "toe"], swap_axes=True, path=out)
    assert out.stat().st_size > 10_000 and len(fig.axes) == 2
    assert math.isfinite(gain_after)


def test_example_file_is_frame_style_with_wheel_points():
    text = (EXAMPLES / "double_wishbone.yaml").read_text()
    assert "projectchrono/chrono" in text and "HMMWV_DoubleWishboneFront" in text
    for name in ("wheel_centre", "spin_axis", "contact_patch", "kingpin: [UBJ, LBJ]", "wheel_centre_ref"):
        assert name in text
