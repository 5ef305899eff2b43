"""The workbench in a real browser: Debian's headless Chromium driven by Playwright.

Loads the page for the double wishbone, edits a hardpoint, waits for the re-assembly and
checks the DOM and the API's numbers against ``kinprop propagate --json`` for the same change;
then a change that cannot be assembled (its reason shown, nothing applied), an input slider,
undo/redo, and that the console stayed free of errors. With ``KINPROP_UPDATE_SCREENSHOT=1``
it writes the screenshot used in docs/guide/serve.md.

Without chromium (or Playwright) the test fails when the environment variable CI is set and
is skipped otherwise (as tests/plot/test_plots.py does).
"""

from __future__ import annotations

import io
import json
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from workbench import cli, cli_json, require_browser

ROOT = Path(__file__).resolve().parents[2]
SCREENSHOT = ROOT / "docs" / "img" / "serve.png"
ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--enable-unsafe-swiftshader",
]
TIMEOUT = 120_000  # ms: a busy 2-core CI machine


def wait_ready(page, before: str) -> None:
    """Wait until the page finished the requests started after revision ``before``."""
    page.wait_for_function(
        f"document.body.dataset.revision !== {json.dumps(before)} && document.body.dataset.state === 'ready'",
        timeout=TIMEOUT,
    )


def edit(page, address: str, index: int, value: str) -> None:
    rev = page.evaluate("document.body.dataset.revision")
    box = page.locator(f'#design input[data-address="{address}"][data-index="{index}"]')
    box.fill(value)
    box.press("Enter")
    wait_ready(page, rev)


def api(page, path: str) -> dict:
    """GET an API path in the page's own session."""
    sid = page.evaluate("sessionStorage.getItem('kinprop-session')")
    r = page.request.get(page.url.rstrip("/") + path, headers={"X-Kinprop-Session": sid})
    assert r.ok, r.text()
    return r.json()


def test_workbench_in_chromium(live_server, examples: Path, tmp_path: Path) -> None:
    exe = require_browser()
    from playwright.sync_api import sync_playwright

    model = examples / "double_wishbone.yaml"
    assembled = tmp_path / "assembled.yaml"
    assert cli("assemble", model, "-o", assembled)[0] == 0  # the session starts assembled, as this file

    console: list[str] = []
    with live_server("double_wishbone.yaml") as srv, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=exe, args=ARGS, headless=True)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.on("console", lambda m: console.append(f"{m.type}: {m.text}") if m.type == "error" else None)
            page.on("pageerror", lambda e: console.append(f"pageerror: {e}"))
            page.goto(srv.url)
            page.wait_for_function("document.body.dataset.state === 'ready'", timeout=TIMEOUT)
            assert "front double wishbone" in page.locator("#model-name").inner_text()
            assert page.locator("#status-text").inner_text().startswith("loaded: converged")
            assert page.locator("#design tbody tr").count() == 11  # every design variable
            assert page.locator("#sliders input[type=range]").count() == 2  # LCA.q, UCA.q
            n_after = page.evaluate("document.getElementById('curves').data.length")
            assert n_after == 2  # camber and toe, no "before" yet

            # --- move the upper arm's front-rear pivot axis up 10 mm -----------------------
            edit(page, "UCA.s_i", 2, "230.091")
            want = cli_json("propagate", assembled, "--set", "UCA.s_i=-158.0642,461.8482,230.091", "--json")
            got = api(page, "/api/results.json")
            assert got == want  # the API's numbers are the CLI's
            # the declared input (LCA, wheel travel) is held; the upper arm follows
            assert got["status"] == "converged" and "LCA.q" not in got["changed"] and "UCA.q" in got["changed"]
            status = page.locator("#status-text").inner_text()
            assert status.startswith("converged") and f"{got['iterations']} iterations" in status
            row = page.locator('#design tr[data-address="UCA.s_i"]')
            assert "role-set" in row.get_attribute("class")
            assert row.locator(".before").inner_text() == "220.091"  # the value before, faded
            assert page.locator("#error").is_hidden()
            # the sliders show the re-assembled coordinates (degrees), as the CLI computed them
            lca = page.locator("#sliders .slider").first.locator(".value").inner_text()
            assert float(lca.split()[0]) == pytest.approx(np.degrees(want["coordinates"]["LCA"][0]), rel=1e-4)
            # 3D: the before scene is drawn faded; curves: before (dashed) and after
            traces = page.evaluate("document.getElementById('view3d').data.map(t => [t.name, t.opacity])")
            assert any(n == "before" and o < 1 for n, o in traces) and any(o == 1 for _, o in traces)
            curves = page.evaluate("document.getElementById('curves').data.map(t => t.name)")
            assert curves == [
                "metric:upright.camber (before)",
                "metric:upright.camber",
                "metric:upright.toe (before)",
                "metric:upright.toe",
            ]
            # the drawn camber curve is the CLI's sweep of the changed design
            state = api(page, "/api/state")
            current = tmp_path / "current.yaml"
            current.write_text(page.request.get(srv.url + "api/model.yaml?session=" + sid(page)).text())
            drive = state["drives"][0]
            spec = f"travel={page.input_value('#drive-from')}:{page.input_value('#drive-to')}:49"
            assert drive["spec"] == "travel"  # a suspension's default drive: wheel travel in equal steps
            sweep = cli_json("sweep", current, "--drive", spec, "--out", "metric:upright.camber", "--json")
            drawn = page.evaluate("document.getElementById('curves').data[1].y")
            assert len(drawn) == 50
            np.testing.assert_allclose(drawn, [r["metric:upright.camber"] for r in sweep["rows"]], rtol=1e-12)
            if os.environ.get("KINPROP_UPDATE_SCREENSHOT"):
                SCREENSHOT.parent.mkdir(parents=True, exist_ok=True)
                page.screenshot(path=str(SCREENSHOT))
            shot = page.screenshot()
            assert_drawn(shot)

            # --- a tie rod 5 m long cannot be assembled: the reason, and nothing applied ----
            yaml_before = current.read_text()
            edit(page, "TR.length", 0, "5000")
            error = page.locator("#error")
            assert error.is_visible()
            text = error.inner_text()
            assert "not applied" in text and "cannot be assembled beyond" in text
            failed = api(page, "/api/results.json")
            assert failed["status"] == "infeasible"
            assert failed["continuation"]["message"] in text  # the CLI's diagnosis, verbatim
            assert page.input_value('#design input[data-address="TR.length"]') == "386.5371"
            assert "failed" in page.locator("#status").get_attribute("class")
            assert page.request.get(srv.url + "api/model.yaml?session=" + sid(page)).text() == yaml_before

            # --- drag an input slider: the mechanism follows along its branch ---------------
            slider = page.locator('#sliders input[data-address="LCA.q"]')
            box = slider.bounding_box()
            y = box["y"] + box["height"] / 2
            page.mouse.move(box["x"] + box["width"] / 2, y)
            page.mouse.down()
            for k in range(1, 11):  # to the right, about 0.9 degrees per move
                page.mouse.move(box["x"] + box["width"] * (0.5 + 0.01 * k), y)
                page.wait_for_timeout(30)
            page.mouse.up()
            page.wait_for_function(
                "document.body.dataset.state === 'ready' && !sliderBusy && !sliderPending", timeout=TIMEOUT
            )
            moved = api(page, "/api/results.json")
            deg = float(slider.input_value())
            assert deg > 5  # the drag moved the slider (the edit left LCA.q at about 0.9 degrees)
            assert moved["status"] == "converged"
            assert moved["coordinates"]["LCA"][0] == pytest.approx(deg, rel=1e-12)  # the last position, model units
            assert api(page, "/api/state")["history"]["undo"] == 2  # the drag is one undo step
            assert page.locator("#error").is_hidden()

            # --- undo twice: the slider move, then the hardpoint edit -----------------------
            for _ in range(2):
                rev = page.evaluate("document.body.dataset.revision")
                page.click("#undo")
                wait_ready(page, rev)
            assert page.input_value('#design input[data-address="UCA.s_i"][data-index="2"]') == "220.091"
            assert page.locator("#undo").is_disabled() and page.locator("#redo").is_enabled()
            rev = page.evaluate("document.body.dataset.revision")
            page.click("#redo")
            wait_ready(page, rev)
            assert page.input_value('#design input[data-address="UCA.s_i"][data-index="2"]') == "230.091"
        finally:
            browser.close()
    assert console == []


def sid(page) -> str:
    return page.evaluate("sessionStorage.getItem('kinprop-session')")


def assert_drawn(png: bytes) -> None:
    """The screenshot shows the mechanism: the 3D view has the wheel upright's red lines."""
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    assert img.shape[:2] == (1000, 1400)
    red = np.all(np.abs(img - [214, 39, 40]) <= 40, axis=-1)  # tab:red, body 'upright'
    assert red[60:520, 600:].sum() > 50, "the 3D view was not drawn"


def test_browser_check_is_not_silently_skipped_in_ci(monkeypatch) -> None:
    """Under CI a missing chromium fails the browser test (outside CI it skips)."""
    import subprocess

    monkeypatch.setattr(shutil, "which", lambda name: None)
    monkeypatch.setattr(subprocess, "run", lambda *a, **k: None)
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="chromium is not installed"):
        require_browser()
    monkeypatch.setenv("CI", "")
    with pytest.raises(pytest.skip.Exception):
        require_browser()
