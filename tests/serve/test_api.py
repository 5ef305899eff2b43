"""The workbench's JSON API against the CLI: the same request gives the same JSON as
``kinprop propagate/check/sweep/sensitivity --json`` (byte for byte), bad input the CLI's
exit-2 messages with HTTP 4xx, and the session keeps an undo/redo history of models."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from workbench import cli, cli_json

MC = "mcpherson.yaml"
DW = "double_wishbone.yaml"


def cli_errors(*args: object) -> list[str]:
    code, out, err = cli(*args)
    assert code == 2, (code, out, err)
    return [line.removeprefix("error: ") for line in err.splitlines() if line.startswith("error: ")]


# --- the CLI's contracts ----------------------------------------------------------------------


def test_propagate_is_the_cli_json(make_client, examples: Path, tmp_path: Path) -> None:
    """The paper's McPherson change (s'12ST moved, free s and l): the API prints what the CLI
    prints; the change is applied, and a second change from the session's model equals the CLI
    run on the model downloaded after the first."""
    c = make_client(MC, assemble_first=False)
    r = c.post("/api/propagate", json={"set": {"ST.s_i": [0.5, 1.0, 0.0]}, "free": ["s", "l"]})
    code, out, _ = cli("propagate", examples / MC, "--set", "ST.s_i=0.5,1.0,0", "--free", "s", "--free", "l", "--json")
    assert r.status_code == 200 and code == 0
    assert r.text == out.rstrip("\n")
    obj = r.json()
    assert obj["status"] == "converged" and obj["residual"] < 1e-10
    assert obj["design"]["ST.s_i"] == [0.5, 1.0, 0.0]
    assert "RS.length" in obj["changed"]
    assert r.headers["x-kinprop-applied"] == "true"

    first = tmp_path / "first.yaml"
    first.write_text(c.get("/api/model.yaml").text)
    r2 = c.post("/api/propagate", json={"set": {"RS.length": 0.21}, "free": ["q"]})
    assert r2.json() == cli_json("propagate", first, "--set", "RS.length=0.21", "--json")
    assert c.get("/api/state").json()["history"] == {"undo": 2, "redo": 0}


def test_propagate_degrees_weights_and_strings(make_client, examples: Path) -> None:
    """Values in the model's units (the double wishbone's angles in degrees), weights, and
    values given as the CLI's text all mean what they mean on the command line."""
    c = make_client(DW, assemble_first=False)
    obj = c.post("/api/propagate", json={"set": {"LCA.q": 3}}).json()
    assert obj == cli_json("propagate", examples / DW, "--set", "LCA.q=3", "--json")
    assert obj["coordinates"]["LCA"][0] == pytest.approx(3.0, abs=1e-12)  # model units (docs/units.md)

    c = make_client(MC, assemble_first=False)
    req = {"set": {"ST.s_i": "0.5,1.0,0"}, "free": ["s", "l"], "weights": {"s": 1, "RS.length": 10}}
    args = ["--set", "ST.s_i=0.5,1.0,0", "--free", "s", "--free", "l", "--weight", "s=1", "--weight", "RS.length=10"]
    assert c.post("/api/propagate", json=req).json() == cli_json("propagate", examples / MC, *args, "--json")


def test_failed_change_is_reported_and_not_applied(make_client, examples: Path) -> None:
    """A tie rod 5 m long cannot be assembled: the CLI's JSON (status not_converged, the
    continuation's diagnosis), HTTP 200, and the session's model is unchanged."""
    c = make_client(DW, assemble_first=False)
    before = c.get("/api/model.yaml").text
    r = c.post("/api/propagate", json={"set": {"TR.length": 5000}})
    code, out, _ = cli("propagate", examples / DW, "--set", "TR.length=5000", "--json")
    assert code == 1 and r.status_code == 200
    obj, cli_obj = r.json(), json.loads(out)
    # the same diagnosis; the iterates of a solve that cannot converge differ in the last bits
    # between processes (threaded BLAS), so compare what the user reads, not every digit
    for key in ("status", "message", "changes", "free", "units"):
        assert obj[key] == cli_obj[key], key
    for key in ("status", "fraction", "message", "conflict"):
        assert obj["continuation"][key] == cli_obj["continuation"][key], key
    assert obj["status"] == "infeasible" and "cannot be assembled" in obj["continuation"]["message"]
    assert r.headers["x-kinprop-applied"] == "false"
    assert c.get("/api/model.yaml").text == before
    assert c.get("/api/state").json()["history"] == {"undo": 0, "redo": 0}
    assert c.get("/api/results.csv").status_code == 409  # the CLI writes no CSV either


def test_check_is_the_cli_json(make_client, examples: Path, tmp_path: Path) -> None:
    c = make_client(MC, assemble_first=False)
    assert c.get("/api/check").text == cli("check", examples / MC, "--json")[1].rstrip("\n")
    # the default session starts assembled: the report of `kinprop assemble -o` 's file
    assembled = tmp_path / "assembled.yaml"
    assert cli("assemble", examples / MC, "-o", assembled)[0] == 0
    got = make_client(MC).get("/api/check").json()
    want = cli_json("check", assembled, "--json")
    assert got.pop("model") == str(examples / MC) and want.pop("model") == str(assembled)
    assert got == want
    assert got["assembled"] and got["mobility"] == 2


def test_sweep_is_the_cli_json(make_client, examples: Path) -> None:
    c = make_client(DW, assemble_first=False)
    r = c.post("/api/sweep", json={"drive": ["LCA=-6:6:6"], "out": ["camber", "toe"]})
    code, out, _ = cli("sweep", examples / DW, "--drive", "LCA=-6:6:6", "--out", "camber", "--out", "toe", "--json")
    assert code == 0 and r.status_code == 200
    assert r.text == out.rstrip("\n")
    rows = r.json()["rows"]
    assert len(rows) == 7 and [x["LCA.q"] for x in rows] == pytest.approx(np.linspace(-6, 6, 7))
    # with a design change and the baseline (the design without it)
    req = {
        "drive": ["LCA=-6:6:4"],
        "set": {"UCA.s_i": [-158.0642, 461.8482, 230.091]},
        "out": ["camber"],
        "baseline": True,
    }
    args = ["--drive", "LCA=-6:6:4", "--set", "UCA.s_i=-158.0642,461.8482,230.091", "--out", "camber", "--baseline"]
    assert c.post("/api/sweep", json=req).json() == cli_json("sweep", examples / DW, *args, "--json")
    assert c.get("/api/state").json()["history"]["undo"] == 0  # a sweep changes nothing


def test_wheel_travel_drive_and_driven_outputs_are_the_cli_json(make_client, examples: Path) -> None:
    """Wheel travel as the drive (equal millimetre steps) and outputs at a travel position
    (issue 20): the API answers what the CLI prints."""
    c = make_client("double_wishbone_hardpoints.yaml", assemble_first=False)
    req = {"drive": ["travel=-30:30:3"], "out": ["camber", "slope:toe@travel=-30..30"]}
    args = ["--drive", "travel=-30:30:3", "--out", "camber", "--out", "slope:toe@travel=-30..30", "--json"]
    r = c.post("/api/sweep", json=req)
    assert r.status_code == 200
    assert r.json() == cli_json("sweep", examples / "double_wishbone_hardpoints.yaml", *args)
    assert [x["travel"] for x in r.json()["rows"]] == [-30.0, -10.0, 10.0, 30.0]
    req = {"wrt": ["hardpoint:TR.i[z]"], "of": ["camber@travel=30", "slope:toe@travel=-30..30"]}
    args = ["--wrt", "hardpoint:TR.i[z]", "--of", "camber@travel=30", "--of", "slope:toe@travel=-30..30", "--json"]
    r = c.post("/api/sensitivity", json=req)
    assert r.status_code == 200
    assert r.json() == cli_json("sensitivity", examples / "double_wishbone_hardpoints.yaml", *args)
    assert r.json()["units"]["of"] == ["deg", "deg/mm"]


def test_sweep_abscissa_is_the_cli_x(make_client, examples: Path, tmp_path: Path) -> None:
    """``x`` (the CLI's ``--x``): camber and toe against wheel travel; the response names it as
    the CLI's JSON does, and without it the first drive."""
    c = make_client(DW, assemble_first=False)
    req = {"drive": ["LCA=-6:6:2"], "out": ["wheel_centre_dz", "camber"], "x": "wheel_centre_dz"}
    args = ["--drive", "LCA=-6:6:2", "--out", "wheel_centre_dz", "--out", "camber", "--x", "wheel_centre_dz"]
    want = cli_json("sweep", examples / DW, *args, "--plot", tmp_path / "x.png", "--json")
    got = c.post("/api/sweep", json=req).json()
    assert got["x"] == want["x"] == "wheel_centre_dz"
    assert got == want | {"plot_file": None}
    assert c.post("/api/sweep", json={"drive": ["LCA=-6:6:2"]}).json()["x"] == "LCA.q"


def test_sensitivity_is_the_cli_json(make_client, examples: Path) -> None:
    c = make_client("slider_crank.yaml", assemble_first=False)
    req = {"wrt": ["J12.s_j"], "of": ["J01.q", "hardpoint:J12.i"]}
    r = c.post("/api/sensitivity", json=req)
    args = ["--wrt", "J12.s_j", "--of", "J01.q", "--of", "hardpoint:J12.i", "--json"]
    assert r.status_code == 200
    assert r.text == cli("sensitivity", examples / "slider_crank.yaml", *args)[1].rstrip("\n")
    assert "not assembled" in r.headers["x-kinprop-note"]  # the CLI's stderr note
    req = {"wrt": ["s"], "free": ["q", "l"], "weights": {"q": 2}}
    args = ["--wrt", "s", "--free", "q", "--free", "l", "--weight", "q=2", "--json"]
    assert c.post("/api/sensitivity", json=req).json() == cli_json("sensitivity", examples / "slider_crank.yaml", *args)


# --- bad input: the CLI's exit-2 messages -------------------------------------------------------


@pytest.mark.parametrize(
    ("path", "body", "args"),
    [
        ("/api/propagate", {"set": {"XX.s_i": [1, 2, 3]}}, ["propagate", "--set", "XX.s_i=1,2,3"]),
        ("/api/propagate", {"set": {"ST.s_i": "a,b"}}, ["propagate", "--set", "ST.s_i=a,b"]),
        ("/api/propagate", {"set": {"ST.s_i": [1, 2]}}, ["propagate", "--set", "ST.s_i=1,2"]),
        ("/api/propagate", {"free": ["zz"]}, ["propagate", "--free", "zz"]),
        ("/api/propagate", {"weights": {"nope": 2}}, ["propagate", "--weight", "nope=2"]),
        ("/api/sweep", {"drive": ["TD=1:2"]}, ["sweep", "--drive", "TD=1:2"]),
        ("/api/sweep", {"drive": ["XX=1:2:3"]}, ["sweep", "--drive", "XX=1:2:3"]),
        (
            "/api/sweep",
            {"drive": ["TD=0.2:0.3:2"], "baseline": True},
            ["sweep", "--drive", "TD=0.2:0.3:2", "--baseline"],
        ),
        (
            "/api/sweep",
            {"drive": ["TD=0.2:0.3:2"], "out": ["point:x"]},
            ["sweep", "--drive", "TD=0.2:0.3:2", "--out", "point:x"],
        ),
        (
            "/api/sweep",
            {"drive": ["TD=0.2:0.3:2"], "x": "nope"},
            ["sweep", "--drive", "TD=0.2:0.3:2", "--x", "nope", "--plot", "x.png"],
        ),
        ("/api/sensitivity", {"wrt": ["RS.nope"]}, ["sensitivity", "--wrt", "RS.nope"]),
        (
            "/api/sensitivity",
            {"wrt": ["s"], "of": ["metric:wheel.camber"]},
            ["sensitivity", "--wrt", "s", "--of", "metric:wheel.camber"],
        ),
    ],
)
def test_bad_input_gets_the_cli_message(make_client, examples: Path, path: str, body: dict, args: list[str]) -> None:
    c = make_client(MC, assemble_first=False)
    before = c.get("/api/model.yaml").text
    r = c.post(path, json=body)
    want = cli_errors(args[0], examples / MC, *args[1:])
    assert r.status_code == 422
    assert r.json() == {"errors": want}
    assert want and all(len(line) > 20 for line in want)  # located messages, not a bare status
    assert c.get("/api/model.yaml").text == before


def test_malformed_requests(make_client) -> None:
    c = make_client(MC, assemble_first=False)
    r = c.post("/api/propagate", content=b"{bad", headers={"Content-Type": "application/json"})
    assert r.status_code == 400 and "invalid JSON" in r.json()["errors"][0]
    r = c.post("/api/propagate", content=b"[1, 2]", headers={"Content-Type": "application/json"})
    assert r.status_code == 400 and r.json()["errors"] == ["request body: expected a JSON object, found '[1, 2]'"]
    r = c.post("/api/propagate", json={"sett": {}})
    assert r.status_code == 422 and r.json()["errors"] == ["body.sett: Extra inputs are not permitted"]
    r = c.post("/api/propagate", json={"set": {"ST.s_i": {"x": 1}}})
    assert r.status_code == 422 and all(e.startswith("body.set.ST.s_i") for e in r.json()["errors"])
    r = c.post("/api/sweep", json={})
    assert r.status_code == 422 and r.json()["errors"] == ["body.drive: Field required"]
    assert c.post("/api/undo").status_code == 409 and c.post("/api/redo").json() == {"errors": ["nothing to redo"]}
    assert c.get("/api/nope").status_code == 404


# --- session: history, downloads, isolation -----------------------------------------------------


def test_undo_redo_reset_and_downloads(make_client, examples: Path, tmp_path: Path) -> None:
    c = make_client(MC, assemble_first=False)
    start = c.get("/api/model.yaml").text
    assert yaml_numbers(start) == yaml_numbers((examples / MC).read_text())
    c.post("/api/propagate", json={"set": {"ST.s_i": [0.5, 1.0, 0.0]}, "free": ["q"]})
    one = c.get("/api/model.yaml").text
    # the downloads are what `kinprop propagate -o/--csv` write and what --json prints
    out_yaml, out_csv = tmp_path / "one.yaml", tmp_path / "one.csv"
    code = cli("propagate", examples / MC, "--set", "ST.s_i=0.5,1.0,0", "-o", out_yaml, "--csv", out_csv)[0]
    assert code == 0
    assert one == out_yaml.read_text()
    assert c.get("/api/results.csv").text == out_csv.read_text()
    res = c.get("/api/results.json")
    assert "attachment" in res.headers["content-disposition"] and res.json()["design"]["ST.s_i"] == [0.5, 1.0, 0.0]
    c.post("/api/propagate", json={"set": {"RS.length": 0.21}})
    two = c.get("/api/model.yaml").text
    assert c.post("/api/undo").json() == {"undo": 1, "redo": 1}
    assert c.get("/api/model.yaml").text == one
    assert c.get("/api/state").json()["before_scene"] is None  # nothing to compare after an undo
    assert c.post("/api/undo").json() == {"undo": 0, "redo": 2}
    assert c.get("/api/model.yaml").text == start
    assert c.post("/api/redo").json() == {"undo": 1, "redo": 1}
    assert c.get("/api/model.yaml").text == one
    assert c.post("/api/redo").json() == {"undo": 2, "redo": 0}
    assert c.get("/api/model.yaml").text == two
    assert c.post("/api/reset").json() == {"undo": 3, "redo": 0}
    assert c.get("/api/model.yaml").text == start
    c.post("/api/undo")
    assert c.get("/api/model.yaml").text == two


def yaml_numbers(text: str) -> dict:
    """The joints' s_i, s_j and lengths in a model file."""
    import yaml

    data = yaml.safe_load(text)
    return {
        j: {k: np.asarray(v, dtype=float).round(12).tolist() for k, v in spec.items() if k in ("s_i", "s_j", "length")}
        for j, spec in data["joints"].items()
    }


def test_slider_moves_coalesce_into_one_undo_step(make_client) -> None:
    c = make_client(DW)
    for deg in (1.0, 2.0, 3.0):
        obj = c.post("/api/propagate", json={"set": {"LCA.q": deg}}).json()
        assert obj["status"] == "converged"
        assert obj["coordinates"]["LCA"][0] == pytest.approx(deg, abs=1e-12)  # model units (docs/units.md)
    assert c.get("/api/state").json()["history"]["undo"] == 1
    c.post("/api/propagate", json={"set": {"TR.length": 390.0}})
    assert c.get("/api/state").json()["history"]["undo"] == 2
    c.post("/api/undo")
    c.post("/api/undo")
    assert c.get("/api/state").json()["coordinates"]["LCA"][0] == pytest.approx(0.0, abs=1e-8)


def test_sessions_are_isolated(make_client) -> None:
    c = make_client(MC)
    a, b = {"X-Kinprop-Session": "a"}, {"X-Kinprop-Session": "b"}
    start = c.get("/api/model.yaml", headers=b).text
    assert c.post("/api/propagate", json={"set": {"RS.length": 0.21}}, headers=a).json()["status"] == "converged"
    assert c.get("/api/model.yaml", headers=b).text == start
    assert c.get("/api/model.yaml", params={"session": "a"}).text != start
    assert c.get("/api/state", headers=a).json()["history"]["undo"] == 1


# --- the page's view ----------------------------------------------------------------------------


def test_state_describes_the_model(make_client) -> None:
    c = make_client(DW)
    st = c.get("/api/state").json()
    assert st["units"]["length"] == "mm" and st["result"]["status"] == "converged"
    assert [s["address"] for s in st["sliders"]] == ["LCA.q"]  # the declared input; UCA.q depends on it
    assert all(s["unit"] == "deg" for s in st["sliders"])
    assert st["default_outputs"] == ["metric:upright.camber", "metric:upright.toe"]
    rows = {v["address"]: v for v in st["variables"]}
    assert rows["TR.length"]["value"] == [pytest.approx(386.5370606)] and rows["TR.length"]["unit"] == "mm"
    assert rows["UBJ.s_j"]["body"] == "upright" and rows["UBJ.s_j"]["group"] == "s"
    # the chassis frame is the global one: a chassis point's s is its global hardpoint
    assert rows["TR.s_i"]["global"] == pytest.approx(rows["TR.s_i"]["value"], abs=1e-9)
    assert rows["TR.s_i"]["global"] == pytest.approx([-250.317, 448.437, 54.229], abs=1e-9)
    # the scene: the tie rod is drawn as a link of its length between its two hardpoints
    tr = next(g for g in st["scene"]["segments"] if g["kind"] == "link")["lines"][0]
    assert np.linalg.norm(np.subtract(tr[1], tr[0])) == pytest.approx(386.5370606, rel=1e-9)
    # after an edit: the set row, the moved rows, the before scene
    c.post("/api/propagate", json={"set": {"TR.length": 390.0}, "free": ["q"]})
    st = c.get("/api/state").json()
    rows = {v["address"]: v for v in st["variables"]}
    assert rows["TR.length"]["role"] == "set" and rows["TR.length"]["before"] == [pytest.approx(386.5370606)]
    # the declared input (LCA, wheel travel) is held; the other coordinates follow
    assert st["before_scene"] is not None and "LCA.q" not in st["changed"] and "UCA.q" in st["changed"]


def test_a_suspension_is_driven_by_wheel_travel(make_client) -> None:
    """The workbench's first drive of a suspension with a wheel-centre reference is the wheel
    travel, +-50 mm (in the model's length unit); a curve's drive, not a slider; without a
    wheel there is none."""
    st = make_client("double_wishbone_hardpoints.yaml").get("/api/state").json()
    travel = st["drives"][0]
    assert (travel["spec"], travel["unit"], travel["curve"]) == ("travel", "mm", [-50.0, 50.0])
    assert [d["spec"] for d in st["sliders"]] == ["LCA"]
    st = make_client("multilink_rear_axle.yaml").get("/api/state").json()
    assert st["drives"][0]["spec"] == "travel" and st["drives"][0]["curve"] == pytest.approx([-0.05, 0.05])  # metres
    assert all(d["spec"] != "travel" for d in make_client("fourbar.yaml").get("/api/state").json()["drives"])


@pytest.mark.parametrize(
    ("name", "edit"),
    [
        ("double_wishbone_hardpoints.yaml", ("hardpoint:UBJ", [-53.0352, 715.518, 225.4936])),  # the UBJ 10 mm up
        ("double_wishbone.yaml", ("UCA.s_i", [-158.0642, 461.8482, 230.091])),  # edits: mechanism, the wheel moves
        ("double_wishbone.yaml", ("hardpoint:UBJ.j", [-53.0352, 725.518, 215.4936])),
    ],
)
def test_the_travel_curve_after_an_edit_is_the_cli_sweep(make_client, examples: Path, tmp_path: Path, name, edit):
    """The page's curve after an edit, as the page asks for it (the state's first drive over its
    default range, the default outputs): the CLI's ``kinprop sweep --drive travel=...`` of the
    edited design (``kinprop propagate ... -o``), row for row, in equal millimetre steps; and
    each row the outputs of the edited model propagated to that row's arm angle."""
    import kinprop as kp

    c = make_client(name)
    address, value = edit
    assert c.post("/api/propagate", json={"set": {address: value}}).json()["status"] == "converged"
    st = c.get("/api/state").json()
    d, outs = st["drives"][0], st["default_outputs"]
    spec = f"{d['spec']}={d['curve'][0]!r}:{d['curve'][1]!r}:49"
    assert spec == "travel=-50.0:50.0:49" and outs == ["metric:upright.camber", "metric:upright.toe"]
    got = c.post("/api/sweep", json={"drive": [spec], "out": outs, "free": ["q"]}).json()
    assembled, changed = tmp_path / "assembled.yaml", tmp_path / "changed.yaml"
    assert cli("assemble", examples / name, "-o", assembled)[0] == 0  # the session starts assembled
    assert cli("propagate", assembled, "--set", f"{address}={','.join(map(repr, value))}", "-o", changed)[0] == 0
    want = cli_json("sweep", changed, "--drive", spec, *[a for o in outs for a in ("--out", o)], "--json")
    assert got["converged"] == want["converged"] == 50
    travel = [r["travel"] for r in got["rows"]]
    np.testing.assert_allclose(np.diff(travel), 100.0 / 49, rtol=1e-12)
    for o in outs:
        np.testing.assert_allclose([r[o] for r in got["rows"]], [r[o] for r in want["rows"]], rtol=1e-9, atol=1e-12)
    if address == "hardpoint:UBJ":  # the numbers of the old mismatch: travel -50 mm, and the arm at -10 deg
        assert got["rows"][0]["metric:upright.camber"] == pytest.approx(1.1711, abs=1e-4)
        arm = c.post("/api/sweep", json={"drive": ["LCA=-10:10:4"], "out": outs[:1]}).json()["rows"][0]
        assert arm["metric:upright.camber"] == pytest.approx(1.6302, abs=1e-4)
    model = kp.load_model(changed)
    for r in got["rows"][::7]:
        at = kp.propagate(model, {"LCA.q": r["LCA.q"]}, tol=1e-12).after
        v = kp.evaluate_outputs(at, [*outs, "metric:upright.wheel_centre_dz"])
        assert v["metric:upright.wheel_centre_dz"] == pytest.approx(r["travel"], abs=1e-8)
        for o in outs:
            assert r[o] == pytest.approx(v[o], abs=1e-9)


def test_curve_defaults_without_a_wheel(make_client) -> None:
    """A four-bar's default curve: the rocker (and coupler) angle over the crank angle; the
    McPherson's drive is the rack (the strut's slide is one coordinate of a 5-coordinate joint)."""
    st = make_client("fourbar.yaml").get("/api/state").json()
    assert st["drives"][0]["spec"] == "O2" and st["default_outputs"] == ["A.q", "O4.q"]
    o2 = st["drives"][0]
    assert o2["unit"] == "deg" and o2["curve"] == pytest.approx([o2["value"] - 10, o2["value"] + 10])
    st = make_client(MC).get("/api/state").json()
    assert [d["spec"] for d in st["drives"]] == ["TD", "ST[4]"] and st["sliders"] == []
    assert st["drives"][0]["unit"] == "m"


def test_sliders_are_the_independent_inputs(make_client) -> None:
    """Sliders for the declared inputs only; without declared inputs, as many single coordinates
    as the mobility, each settable on its own (the slider-crank: one of its three revolutes and
    slider, not a dependent one; checked by setting it: the propagation converges)."""
    st = make_client("fourbar.yaml").get("/api/state").json()
    assert [s["address"] for s in st["sliders"]] == ["O2.q"]
    c = make_client("slider_crank.yaml")
    st = c.get("/api/state").json()
    assert c.get("/api/check").json()["mobility"] == len(st["sliders"]) == 1
    s = st["sliders"][0]
    r = c.post("/api/propagate", json={"set": {s["address"]: s["value"] + 0.1}})
    assert r.json()["status"] == "converged"


def test_status_line_is_the_last_applied_change(make_client) -> None:
    """The status line names the change that made the current model; a refused change leaves it;
    undo says so and shows the model it went back to."""
    c = make_client("double_wishbone.yaml")
    assert c.get("/api/state").json()["status_line"].startswith("loaded: converged")
    r = c.post("/api/propagate", json={"set": {"LCA.q": 3.0}}).json()
    line = c.get("/api/state").json()["status_line"]
    assert line.startswith("LCA.q = 3: converged") and f"{r['iterations']} iterations" in line
    assert c.post("/api/propagate", json={"set": {"TR.length": 5000.0}}).json()["status"] != "converged"
    assert c.get("/api/state").json()["status_line"] == line
    c.post("/api/undo")
    assert c.get("/api/state").json()["status_line"].startswith("undo: loaded: converged")
    c.post("/api/redo")
    assert c.get("/api/state").json()["status_line"] == "redo: " + line


def test_page_and_static_files(make_client) -> None:
    c = make_client(MC)
    page = c.get("/")
    assert page.status_code == 200 and '<div id="view3d"' in page.text
    assert "http" not in page.text.replace("http-equiv", "")  # no CDN: everything from this server
    js = c.get("/static/plotly.min.js")
    assert js.status_code == 200 and len(js.content) > 1_000_000 and b"plotly.js" in js.content[:2000]
    for name in ("app.js", "style.css"):
        assert c.get(f"/static/{name}").status_code == 200


def test_serve_command_errors(examples: Path, tmp_path: Path) -> None:
    """`kinprop serve` rejects a bad model like the other commands (exit 2, located message)."""
    bad = tmp_path / "bad.yaml"
    bad.write_text((examples / MC).read_text().replace("length: 0.203", "length: [1, 2]"))
    assert cli_errors("serve", bad) == cli_errors("check", bad)
    assert cli_errors("serve", tmp_path / "missing.yaml") == cli_errors("check", tmp_path / "missing.yaml")
    code, _, err = cli("serve", examples / MC, "--port", "0")
    assert code == 2 and "--port 0" in err


def test_serve_command_serves(examples: Path) -> None:
    """`kinprop serve MODEL --port P` prints its URL (localhost by default) and answers there."""
    import subprocess
    import sys
    import time
    import urllib.request

    from workbench import free_port

    port = free_port()
    code = "from kinprop.cli import main; import sys; sys.argv = ['kinprop', *sys.argv[1:]]; main()"
    args = ["serve", str(examples / MC), "--port", str(port)]
    proc = subprocess.Popen([sys.executable, "-c", code, *args], stdout=subprocess.PIPE, text=True)
    try:
        line = proc.stdout.readline()
        url = f"http://127.0.0.1:{port}/"
        assert url in line and "mcpherson.yaml" in line
        deadline = time.monotonic() + 60
        while True:
            try:
                with urllib.request.urlopen(url + "api/check", timeout=5) as r:
                    obj = json.loads(r.read())
                break
            except OSError:
                if time.monotonic() > deadline or proc.poll() is not None:
                    raise
                time.sleep(0.1)
        assert obj["model"] == str(examples / MC) and obj["assembled"] and obj["mobility"] == 2
    finally:
        proc.terminate()
        proc.wait(timeout=30)


def test_an_axle_is_driven_by_roll_and_steer_too(make_client, examples: Path) -> None:
    """An axle with a rack also offers body roll (+-2 deg) and the first wheel's road-wheel
    steer (+-20 deg) as drives of the page, and the API's curve over each is the CLI sweep's."""
    name = "hmmwv_front_axle.yaml"
    c = make_client(name, assemble_first=False)
    drives = {d["spec"]: d for d in c.get("/api/state").json()["drives"]}
    assert list(drives)[:3] == ["travel", "roll", "steer:upright_L"]
    assert (drives["roll"]["unit"], drives["roll"]["curve"]) == ("deg", [-2.0, 2.0])
    assert drives["steer:upright_L"]["curve"] == [-20.0, 20.0]
    for spec in ("roll=-2:2:4", "steer:upright_L=-20:20:4"):
        req = {"drive": [spec], "out": ["metric:upright_L.toe", "metric:upright_R.camber"]}
        args = ["--drive", spec, "--out", "metric:upright_L.toe", "--out", "metric:upright_R.camber", "--json"]
        r = c.post("/api/sweep", json=req)
        assert r.status_code == 200, r.text
        assert r.json() == cli_json("sweep", examples / name, *args)
    single = {d["spec"] for d in make_client("double_wishbone_hardpoints.yaml").get("/api/state").json()["drives"]}
    assert "roll" not in single  # one wheel: no body roll
