"""``dir(kinprop)`` lists the public API, not the helpers the package imports (issue 19 item 11)."""

from __future__ import annotations

import kinprop


def test_dir_is_the_public_api():
    public = [n for n in dir(kinprop) if not n.startswith("_")]
    assert public == sorted(kinprop.__all__)
    assert not {"Any", "TYPE_CHECKING", "importlib"} & set(dir(kinprop))
    assert all(getattr(kinprop, n) is not None for n in kinprop.__all__)


def test_propagate_quiet_prints_the_outcome_only():
    from pathlib import Path

    from typer.testing import CliRunner

    from kinprop.cli import app

    ex = Path(__file__).resolve().parents[1] / "examples" / "fourbar.yaml"
    r = CliRunner().invoke(app, ["propagate", str(ex), "--set", "O2.q=70", "-q"])
    assert r.exit_code == 0, r.output
    lines = [ln for ln in r.stdout.splitlines() if ln.strip()]
    assert len(lines) == 1 and lines[0].startswith("converged in ")
