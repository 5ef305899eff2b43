"""Units a person can get wrong (issue 19 item 5): warnings on implausible scales, and the
declared units kept through an MJCF round trip.

Truth for the round trip: the original model's own solve (the same wheel centre at LCA = 5
deg, in mm); for the warnings, the sizes are set here (a 470 "m" tyre on a 0.4 m suspension,
millimetre numbers under ``length: m``).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from typer.testing import CliRunner

from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
runner = CliRunner()


def run(*args: object):
    return runner.invoke(app, [str(a) for a in args])


@pytest.mark.parametrize(("radius", "warned"), [(470, True), (0.47, False)])
def test_tyre_radius_in_the_wrong_unit_is_warned(tmp_path, radius, warned):
    r = run("import", EXAMPLES / "chrono" / "DoubleWishbone.json", "--tire-radius", radius, "-o", tmp_path / "dw.yaml")
    assert r.exit_code == 0, r.output
    assert ("loaded radius 470 m" in r.stderr) is warned, r.stderr


def test_millimetre_numbers_under_length_m_are_warned(tmp_path):
    text = (EXAMPLES / "double_wishbone_hardpoints.yaml").read_text()
    wrong = tmp_path / "wrong.yaml"
    wrong.write_text(text.replace("length: mm", "length: m"))
    r = run("check", wrong)
    assert r.exit_code == 0, r.output
    assert "look like millimetres, but the file declares length: m" in r.stderr
    r = run("check", EXAMPLES / "double_wishbone_hardpoints.yaml")
    assert r.exit_code == 0 and "warning" not in r.stderr


def test_mjcf_round_trip_keeps_the_declared_units(tmp_path):
    src = EXAMPLES / "double_wishbone_hardpoints.yaml"
    assert run("convert", src, "--to", "mjcf", "-o", tmp_path / "dw.xml").exit_code == 0
    r = run("import", tmp_path / "dw.xml", "-o", tmp_path / "back.yaml")
    assert r.exit_code == 0, r.output
    back = yaml.safe_load((tmp_path / "back.yaml").read_text())
    assert {k: back["units"][k] for k in ("length", "angle", "axes")} == {
        "length": "mm",
        "angle": "deg",
        "axes": "ISO8855",
    }
    got = json.loads(run("propagate", tmp_path / "back.yaml", "--set", "LCA.q=5", "--free", "q", "--json").stdout)
    want = json.loads(run("propagate", src, "--set", "LCA.q=5", "--json").stdout)
    assert got["coordinates"]["LCA"] == pytest.approx([5.0])  # degrees, as declared
    np.testing.assert_allclose(got["points"]["upright.wheel_centre"], want["points"]["upright.wheel_centre"], atol=1e-6)


def test_python_api_warns_as_the_cli_does(tmp_path):
    """``load_model`` and ``import_model`` issue a :class:`kinprop.UnitsWarning` with the CLI's
    text; a plausible file gives none."""
    import warnings

    import kinprop as kp
    from kinprop.imports import import_model

    text = (EXAMPLES / "double_wishbone_hardpoints.yaml").read_text()
    wrong = tmp_path / "wrong.yaml"
    wrong.write_text(text.replace("length: mm", "length: m"))
    with pytest.warns(kp.UnitsWarning, match="look like millimetres, but the file declares length: m") as rec:
        kp.load_model(wrong)
    assert rec[0].filename == __file__  # points at the caller, not at kinprop's insides
    assert str(wrong) in str(rec[0].message)
    with pytest.warns(kp.UnitsWarning, match="loaded radius 470 m"):
        import_model(EXAMPLES / "chrono" / "DoubleWishbone.json", tire_radius=470)
    with warnings.catch_warnings():
        warnings.simplefilter("error", kp.UnitsWarning)
        kp.load_model(EXAMPLES / "double_wishbone_hardpoints.yaml")
        import_model(EXAMPLES / "chrono" / "DoubleWishbone.json", tire_radius=0.47)
