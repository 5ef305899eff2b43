"""Plots: the stick-figure geometry, PNG and HTML files, and the HTML rendered by headless Chromium.

The browser is Debian's ``chromium`` (installed by scripts/install-test-deps.sh). Without it
the browser test fails when the environment variable CI is set and is skipped otherwise.
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from typer.testing import CliRunner

from kinprop import load_model, propagate
from kinprop.cli import app
from kinprop.plot import build_scene, save_plot

ROOT = Path(__file__).resolve().parents[2]
runner = CliRunner()


def run(*args: object):
    return runner.invoke(app, [str(a) for a in args])


@pytest.fixture(scope="module")
def mcpherson_pair(examples):
    """(before, after): the assembled McPherson strut, then s'12ST moved (the paper's Figs. 5-6)."""
    base = propagate(load_model(examples / "mcpherson.yaml")).after
    return base, propagate(base, {"ST.s_i": [0.5, 1.0, 0.0]}, ("s", "q")).after


def seg_lengths(scene, kind: str, owner: str) -> list[float]:
    return [float(np.linalg.norm(s.end - s.start)) for s in scene.segments if s.kind == kind and s.owner == owner]


# --- geometry ---------------------------------------------------------------------------------


def test_scene_mcpherson_links_and_axes(mcpherson_pair) -> None:
    _, after = mcpherson_pair
    sc = build_scene(after)
    assert sc.unit == "m" and sc.bodies == ("chassis", "wheel")
    # the lower arm and the tie rod keep their lengths at an assembled state
    assert seg_lengths(sc, "link", "RS") == [pytest.approx(0.203, abs=1e-9)]
    assert seg_lengths(sc, "link", "TD") == [pytest.approx(0.3742, abs=1e-9)]
    # the rack travel is q3 and the strut travel |q2|
    assert seg_lengths(sc, "slide", "TD") == [pytest.approx(abs(after.coordinates["TD"][0]), abs=1e-12)]
    assert seg_lengths(sc, "slide", "ST") == [pytest.approx(abs(after.coordinates["ST"][4]), abs=1e-12)]
    assert {(m.joint, m.kind) for m in sc.markers} >= {("RS", "revolute"), ("RS", "spherical"), ("ST", "spherical")}
    assert {a.joint for a in sc.axes} == {"ST", "RS", "TD"}
    for a in sc.axes:
        assert np.linalg.norm(a.direction) == pytest.approx(1.0)
    assert not [s for s in sc.segments if s.kind == "gap"]


def test_scene_slider_crank(examples) -> None:
    m = load_model(examples / "slider_crank.yaml")
    assembled = propagate(m).after
    sc = build_scene(assembled)
    assert seg_lengths(sc, "body", "crank") == [pytest.approx(2.0)]  # |s'12|
    u = [a for a in sc.axes if a.joint == "J32"]
    assert [a.label for a in u] == ["z''", "y''"]  # both axes of the universal joint
    assert float(u[0].direction @ u[1].direction) == pytest.approx(0.0, abs=1e-12)
    assert not [s for s in sc.segments if s.kind == "gap"]
    # the file's starting estimates leave the cut spherical joint open: drawn as a gap
    gaps = [s for s in build_scene(m).segments if s.kind == "gap"]
    assert [g.owner for g in gaps] == ["J12"]


# --- files ------------------------------------------------------------------------------------


def png_pixels(data: bytes) -> np.ndarray:
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"))


def assert_not_blank(img: np.ndarray) -> None:
    non_white = np.any(img < 235, axis=-1).mean()
    assert non_white > 0.01, f"only {non_white:.2%} of the pixels are drawn"
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 50


def test_plot_png_cli(examples, tmp_path) -> None:
    out = tmp_path / "sc.png"
    r = run("plot", examples / "slider_crank.yaml", "-o", out)
    assert r.exit_code == 0, r.output
    assert "wrote" in r.stdout
    assert "not assembled" in r.stderr  # drawn as given, and says so
    img = png_pixels(out.read_bytes())
    assert img.shape[0] > 400 and img.shape[1] > 600
    assert_not_blank(img)


def test_plot_compare_html_cli(examples, tmp_path) -> None:
    a = tmp_path / "assembled.yaml"
    assert run("assemble", examples / "mcpherson.yaml", "-o", a).exit_code == 0
    out = tmp_path / "cmp.html"
    r = run("plot", a, "--compare", examples / "mcpherson.yaml", "-o", out)
    assert r.exit_code == 0, r.output
    html = out.read_text()
    assert "plotly" in html.lower() and "Plotly.newPlot" in html
    assert "<script src=" not in html  # self-contained: plotly.js is inlined, works offline
    assert "after: assembled.yaml" in html and "before: mcpherson.yaml" in html
    assert "x [m]" in html and "scatter3d" in html


def test_propagate_plot_png_and_html(examples, tmp_path) -> None:
    for name in ("mc.png", "mc.html"):
        out = tmp_path / name
        r = run("propagate", examples / "mcpherson.yaml", "--set", "ST.s_i=0.5,1.0,0", "--free", "s", "--plot", out)
        assert r.exit_code == 0, r.output
        assert out.stat().st_size > 10_000
    assert_not_blank(png_pixels((tmp_path / "mc.png").read_bytes()))
    html = (tmp_path / "mc.html").read_text()
    assert '"before"' in html and '"after"' in html


def test_bad_plot_suffix_exit_2(examples, tmp_path) -> None:
    r = run("plot", examples / "slider_crank.yaml", "-o", tmp_path / "x.svg")
    assert r.exit_code == 2 and "expected a name ending in .png or .html" in r.stderr
    r = run("propagate", examples / "slider_crank.yaml", "--plot", tmp_path / "x.pdf")
    assert r.exit_code == 2 and not (tmp_path / "x.pdf").exists()


def test_save_plot_library(mcpherson_pair, tmp_path) -> None:
    before, after = mcpherson_pair
    path = save_plot(tmp_path / "sub" / "fig.png", after, before, title="McPherson: s'12ST moved")
    assert path.exists() and not list(path.parent.glob(".*.tmp"))  # atomic, no leftovers
    assert_not_blank(png_pixels(path.read_bytes()))


# --- the HTML in a real browser ---------------------------------------------------------------


def require_chromium() -> str:
    """The chromium executable; under CI try the installer once, then fail loudly."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    ci = bool(os.environ.get("CI"))
    if exe is None and ci:
        with contextlib.suppress(OSError, subprocess.SubprocessError):
            subprocess.run(["bash", str(ROOT / "scripts" / "install-test-deps.sh")], capture_output=True, timeout=1200)
        exe = shutil.which("chromium")
    if exe is None:
        msg = "chromium is not installed (Debian package 'chromium'; run scripts/install-test-deps.sh)"
        if ci:
            pytest.fail(f"{msg}: the browser test cannot run under CI", pytrace=False)
        pytest.skip(msg)
    return exe


@pytest.mark.parametrize("ci", ["1", ""])
def test_missing_chromium_fails_under_ci_else_skips(monkeypatch, ci: str) -> None:
    calls = []
    monkeypatch.setattr(shutil, "which", lambda name: None)
    monkeypatch.setattr(subprocess, "run", lambda *a, **k: calls.append(a))
    monkeypatch.setenv("CI", ci)
    expected = pytest.fail.Exception if ci else pytest.skip.Exception
    with pytest.raises(expected, match="chromium is not installed"):
        require_chromium()
    assert len(calls) == (1 if ci else 0)  # the installer is tried under CI only


def chromium(exe: str, profile: Path, *args: str) -> subprocess.CompletedProcess:
    cmd = [
        exe,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--enable-unsafe-swiftshader",  # software WebGL for plotly's 3D scene (trusted local file)
        "--disable-quic",
        "--no-first-run",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        f"--user-data-dir={profile}",
        "--virtual-time-budget=10000",
        *args,
    ]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=240)


def test_html_renders_in_headless_chromium(mcpherson_pair, tmp_path) -> None:
    exe = require_chromium()
    before, after = mcpherson_pair
    html = save_plot(tmp_path / "fig.html", after, before)
    shot = tmp_path / "shot.png"
    proc = chromium(exe, tmp_path / "profile", f"--screenshot={shot}", "--window-size=1000,800", html.as_uri())
    assert shot.exists(), f"no screenshot: {proc.stderr[-2000:]}"
    img = png_pixels(shot.read_bytes())
    assert img.shape[:2] == (800, 1000)
    assert_not_blank(img)
    # in the plot area (left of the legend, below the title) WebGL drew the wheel's orange lines
    region = img[60:, :700].astype(int)
    orange = np.all(np.abs(region - [255, 127, 14]) <= 40, axis=-1).sum()
    assert orange > 30, f"the 3D scene was not drawn ({orange} orange pixels)"

    dom = chromium(exe, tmp_path / "profile2", "--dump-dom", html.as_uri()).stdout
    assert 'class="main-svg"' in dom and "gl-container" in dom
    assert 'class="no-webgl"' not in dom  # plotly's "WebGL is not supported" overlay
