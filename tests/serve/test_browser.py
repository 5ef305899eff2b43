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
            assert page.locator("#body-frames").get_attribute("open") is not None  # a frame-style file
            # the declared input only: UCA.q depends on LCA.q (mobility 1), no slider for it
            assert page.locator("#sliders input[type=range]").count() == 1
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
            assert status.startswith("UCA.s_i = [-158.0642, 461.8482, 230.091]: converged")
            assert f"{got['iterations']} iterations" in status
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
            # the status line still tells the last applied change (the failed one is not applied)
            assert page.locator("#status-text").inner_text() == status
            assert page.request.get(srv.url + "api/model.yaml?session=" + sid(page)).text() == yaml_before

            # --- drag an input slider: the mechanism follows along its branch ---------------
            slider = page.locator('#sliders input[data-address="LCA.q"]')
            slider.scroll_into_view_if_needed()
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
            # the status line is the last applied slider position, as the slider shows it
            assert page.locator("#status-text").inner_text().startswith(f"LCA.q = {deg:.7g}: converged")

            # --- undo twice: the slider move, then the hardpoint edit -----------------------
            for _ in range(2):
                rev = page.evaluate("document.body.dataset.revision")
                page.click("#undo")
                wait_ready(page, rev)
            assert page.input_value('#design input[data-address="UCA.s_i"][data-index="2"]') == "220.091"
            assert page.locator("#undo").is_disabled() and page.locator("#redo").is_enabled()
            assert page.locator("#status-text").inner_text().startswith("undo: loaded: converged")
            rev = page.evaluate("document.body.dataset.revision")
            page.click("#redo")
            wait_ready(page, rev)
            assert page.input_value('#design input[data-address="UCA.s_i"][data-index="2"]') == "230.091"
        finally:
            browser.close()
    assert console == []


def test_hardpoints_and_views_in_chromium(live_server, examples: Path, tmp_path: Path) -> None:
    """A hardpoint-style file: the design table lists the global hardpoints in suspension order;
    editing one (the upper ball joint 10 mm up) gives the camber curve and hardpoints that
    ``kinprop propagate --set hardpoint:UBJ=...`` and ``kinprop sweep`` give; only the declared
    input has a slider; the front, side and top views are orthographic; the wheel and ground are
    drawn; the console stays free of errors."""
    exe = require_browser()
    from playwright.sync_api import sync_playwright

    model = examples / "double_wishbone_hardpoints.yaml"
    assembled = tmp_path / "assembled.yaml"
    assert cli("assemble", model, "-o", assembled)[0] == 0
    console: list[str] = []
    with live_server("double_wishbone_hardpoints.yaml") as srv, sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=exe, args=ARGS, headless=True)
        try:
            page = browser.new_page(viewport={"width": 1400, "height": 1000})
            page.on("console", lambda m: console.append(f"{m.type}: {m.text}") if m.type == "error" else None)
            page.on("pageerror", lambda e: console.append(f"pageerror: {e}"))
            page.goto(srv.url)
            page.wait_for_function("document.body.dataset.state === 'ready'", timeout=TIMEOUT)
            # body-frame rows out of the way; the hardpoints in suspension order
            assert page.locator("#body-frames").get_attribute("open") is None
            sections = page.locator("#hardpoints tr.section").all_inner_texts()
            assert sections == ["chassis pickups", "upright points", "steering", "spring/damper", "wheel"]
            editable = page.eval_on_selector_all(
                "#hardpoints input[data-index='0']", "els => els.map(e => e.dataset.hardpoint)"
            )
            assert editable == [
                "hardpoint:LCA.front", "hardpoint:LCA.rear", "hardpoint:UCA.front", "hardpoint:UCA.rear",
                "hardpoint:LBJ", "hardpoint:UBJ", "hardpoint:TR.i", "hardpoint:TR.j",
            ]  # fmt: skip
            # the file's numbers (global, mm), as written
            assert page.input_value('#hardpoints input[data-hardpoint="hardpoint:TR.i"][data-index="2"]') == "54.229"
            assert [s["address"] for s in api(page, "/api/state")["sliders"]] == ["LCA.q"]
            assert page.locator("#sliders input[type=range]").count() == 1

            # --- the upper ball joint 10 mm up, in global coordinates ------------------------
            rev = page.evaluate("document.body.dataset.revision")
            box = page.locator('#hardpoints input[data-hardpoint="hardpoint:UBJ"][data-index="2"]')
            box.fill("225.4936")
            box.press("Enter")
            wait_ready(page, rev)
            assert page.locator("#error").is_hidden()
            target = "hardpoint:UBJ=-53.0352,715.518,225.4936"
            want = cli_json("propagate", assembled, "--set", target, "--json")
            got = api(page, "/api/results.json")
            assert got["status"] == want["status"] == "converged" and got["changed"] == want["changed"]
            for key in ("hardpoints", "points"):  # assembled.yaml is written at full precision (1e-12 mm)
                assert got[key].keys() == want[key].keys()
                np.testing.assert_allclose(list(got[key].values()), list(want[key].values()), rtol=0, atol=1e-9)
            ubj = page.eval_on_selector_all(
                '#hardpoints input[data-hardpoint="hardpoint:UBJ"]', "els => els.map(e => Number(e.value))"
            )
            np.testing.assert_allclose(ubj, want["hardpoints"]["UBJ.i"], rtol=1e-7)  # the row shows the result
            assert (
                page.locator("#status-text")
                .inner_text()
                .startswith("hardpoint:UBJ = [-53.0352, 715.518, 225.4936]: converged")
            )
            changed = tmp_path / "changed.yaml"
            assert cli("propagate", assembled, "--set", target, "-o", changed)[0] == 0
            spec = f"travel={page.input_value('#drive-from')}:{page.input_value('#drive-to')}:49"
            sweep = cli_json("sweep", changed, "--drive", spec, "--out", "metric:upright.camber", "--json")
            base = cli_json("sweep", assembled, "--drive", spec, "--out", "metric:upright.camber", "--json")
            data = page.evaluate("document.getElementById('curves').data.map(t => [t.name, t.y])")
            drawn = dict(data)
            cli_after = [r["metric:upright.camber"] for r in sweep["rows"]]
            cli_before = [r["metric:upright.camber"] for r in base["rows"]]
            np.testing.assert_allclose(drawn["metric:upright.camber"], cli_after, rtol=1e-9, atol=1e-12)
            np.testing.assert_allclose(drawn["metric:upright.camber (before)"], cli_before, rtol=1e-9, atol=1e-12)
            assert np.max(np.abs(np.subtract(cli_after, cli_before))) > 1e-3  # the edit moved the curve
            assert page.input_value('#hardpoints input[data-hardpoint="hardpoint:UBJ"][data-index="2"]') == "225.4936"

            # --- views: orthographic front, side and top; the tyre, its spin axis, the ground -
            names = page.evaluate("document.getElementById('view3d').data.map(t => t.name)")
            assert {"tyre upright", "spin axis upright", "ground plane"} <= set(names)
            ground = page.evaluate("document.getElementById('view3d').data.find(t => t.name === 'ground plane').z")
            assert ground == pytest.approx([-496.289] * 4)  # the contact patch's height (file: z = -496.289)
            modes = page.evaluate("document.getElementById('view3d').data.map(t => t.mode || '')")
            assert not any("text" in m for m in modes)  # labels on hover only
            eyes = {}
            for v in ("front", "side", "top"):
                page.click(f'#views button[data-view="{v}"]')
                page.wait_for_function(f"document.body.dataset.view === '{v}'", timeout=TIMEOUT)
                cam = page.evaluate("document.getElementById('view3d').layout.scene.camera")
                assert cam["projection"]["type"] == "orthographic"
                eyes[v] = cam["eye"]
            assert eyes["front"]["x"] > 0 and eyes["front"]["y"] == 0 == eyes["front"]["z"]  # looking rearward
            assert eyes["side"]["y"] > 0 and eyes["side"]["x"] == 0 == eyes["side"]["z"]
            assert eyes["top"]["z"] > 0 and eyes["top"]["x"] == 0 == eyes["top"]["y"]
            if os.environ.get("KINPROP_UPDATE_SCREENSHOT"):
                page.screenshot(path=str(SCREENSHOT.with_name("serve-hardpoints.png")))

            # --- the report of the edited design: downloaded, opened (no network), its numbers
            with page.expect_download() as dl:
                page.click("#dl-report")
            report = tmp_path / "report.html"
            dl.value.save_as(report)
            page.goto(report.as_uri())
            page.wait_for_function("document.getElementById('curves') && document.getElementById('curves').data")
            assert page.evaluate("document.getElementById('curves').data.length") == 2  # camber, toe
            np.testing.assert_allclose(
                page.evaluate("document.getElementById('curves').data[0].y"), cli_after, rtol=1e-9, atol=1e-12
            )
            assert "225.4936" in page.locator("#hardpoints").inner_text()
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
