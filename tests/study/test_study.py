"""Design studies: sampling, agreement with propagate, streaming, resume, CLI exit codes."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from kinprop import propagate
from kinprop.analysis.study import Factor, parse_vary, read_study, run_study, sample_plan
from kinprop.builders import rssr
from kinprop.cli import app
from kinprop.errors import AddressError
from kinprop.io import load_model

FACTORS = [Factor("coupler.length", 0.30, 0.32), Factor("rocker.s_i[0]", 0.34, 0.36)]
FREE = ("rocker.q",)


def test_sample_plans():
    g = sample_plan(FACTORS, "grid", 3)
    assert g.shape == (9, 2) and set(np.round(g[:, 0], 6)) == {0.30, 0.31, 0.32}
    lhs = sample_plan(FACTORS, "lhs", 20, seed=1)
    assert lhs.shape == (20, 2)
    # Latin hypercube: one sample in each of the 20 strata of every factor
    strata = np.floor((lhs[:, 0] - 0.30) / 0.02 * 20).astype(int)
    assert sorted(strata) == list(range(20))
    mc = sample_plan(FACTORS, "mc", 10, seed=3)
    np.testing.assert_array_equal(mc, sample_plan(FACTORS, "mc", 10, seed=3))
    assert parse_vary("RS.s_i[2]=-0.4:-0.38") == Factor("RS.s_i[2]", -0.4, -0.38)
    for bad in ("RS.s_i[2]", "RS.s_i[2]=1", "x=2:1"):
        with pytest.raises(AddressError):
            parse_vary(bad)


@pytest.mark.parametrize("engine", ["auto", "reference"])
def test_study_matches_propagate(engine):
    model = rssr(theta=1.0)
    df = run_study(model, FACTORS, method="lhs", samples=12, seed=2, free=FREE, chunk_size=5, engine=engine)
    assert isinstance(df, pd.DataFrame) and len(df) == 12 and df["converged"].all()
    assert list(df["variant"]) == list(range(12))
    for k in (0, 7, 11):
        ch = {f.address: df[f.address][k] for f in FACTORS}
        ref = propagate(model, ch, FREE)
        assert df["iterations"][k] == ref.result.iterations
        assert df["rocker.q"][k] == pytest.approx(ref.after.coordinates["rocker"][0], abs=1e-10)
        phi = ref.after.coordinates["rocker"][0]
        ball = np.asarray(ch and ref.after.design["rocker.s_i"]) + 0.3 * np.array([np.sin(phi), 0, np.cos(phi)])
        assert df["point:rocker.ball[x]"][k] == pytest.approx(ball[0], abs=1e-10)
        assert df["point:rocker.ball[z]"][k] == pytest.approx(ball[2], abs=1e-10)


def test_fast_and_reference_engines_agree(examples):
    pytest.importorskip("numba")
    model = load_model(examples / "mcpherson.yaml")
    f = [Factor("RS.length", 0.20, 0.21), Factor("TD.s_j[1]", 0.15, 0.16)]
    sets = {"ST.s_i": [0.5, 1.0, 0.0]}
    a = run_study(model, f, method="mc", samples=6, sets=sets, engine="fast")
    b = run_study(model, f, method="mc", samples=6, sets=sets, engine="reference")
    assert list(a.columns) == list(b.columns)
    num = [c for c in a.columns if c not in ("status",)]
    np.testing.assert_allclose(a[num].astype(float).to_numpy(), b[num].astype(float).to_numpy(), atol=1e-9)


def test_interrupted_study_resumes(tmp_path):
    model = rssr(theta=1.0)
    full = run_study(model, FACTORS, method="grid", samples=5, free=FREE, chunk_size=4)
    out = tmp_path / "results.parquet"

    def abort_after_two(chunk):
        if chunk == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study(
            model, FACTORS, method="grid", samples=5, free=FREE, chunk_size=4, output=out, on_chunk=abort_after_two
        )
    kept = read_study(out)
    assert len(kept) == 12  # chunks 0, 1, 2 were stored before the abort
    assert not list(out.glob(".*tmp"))
    computed: list[int] = []
    with pytest.raises(AddressError, match="--resume"):
        run_study(model, FACTORS, method="grid", samples=5, free=FREE, chunk_size=4, output=out)
    done = run_study(model, FACTORS, method="grid", samples=5, free=FREE, chunk_size=4, output=out, resume=True,
                     on_chunk=computed.append)  # fmt: skip
    assert computed == [3, 4, 5, 6]
    pd.testing.assert_frame_equal(done, full)
    pd.testing.assert_frame_equal(pd.read_parquet(out).sort_values("variant", ignore_index=True), full)
    with pytest.raises(AddressError, match="differs"):
        run_study(model, FACTORS, method="grid", samples=4, free=FREE, chunk_size=4, output=out, resume=True)


def test_cli_study_resume_after_truncation(tmp_path, rssr_file):
    runner = CliRunner()
    out = tmp_path / "r.parquet"
    vary = ["--vary", "coupler.length=0.30:0.32", "--vary", "rocker.s_i[0]=0.34:0.36"]
    opts = ["--method", "lhs", "--samples", "40", "--seed", "4", "--free", "rocker.q", "--chunk-size", "8"]
    args = ["study", str(rssr_file), *vary, *opts, "-o", str(out)]
    r = runner.invoke(app, [*args, "--json"])
    assert r.exit_code == 0, r.output
    assert json.loads(r.output) == {"variants": 40, "failed": 0, "output": str(out)}
    full = read_study(out)
    for p in sorted(out.glob("part-*.parquet"))[2:4]:  # lose two chunks, as if killed mid-study
        p.unlink()
    assert len(read_study(out)) == 24
    r = runner.invoke(app, [*args, "--resume"])
    assert r.exit_code == 0, r.output
    pd.testing.assert_frame_equal(read_study(out), full)


def test_cli_exit_codes(tmp_path, rssr_file):
    runner = CliRunner()
    base = ["study", str(rssr_file), "--free", "rocker.q", "--samples", "6"]
    # some variants cannot assemble (coupler too long): recorded, exit 1
    r = runner.invoke(app, [*base, "--vary", "coupler.length=0.3:3.0", "--method", "grid", "-o", str(tmp_path / "a")])
    assert r.exit_code == 1, r.output
    df = read_study(tmp_path / "a")
    assert (~df["converged"]).sum() > 0 and df["converged"].sum() > 0
    assert df.loc[~df["converged"], "rocker.q"].isna().all()
    bads = (
        ["--vary", "nojoint.length=1:2"],
        ["--vary", "rocker.C_i[0]=0:1"],
        ["--vary", "rocker.s_i=0:1"],
        ["--vary", "coupler.length=2:1"],
        ["--vary", "coupler.length=0.3:0.31", "--method", "sobol"],
    )
    for bad in bads:
        r = runner.invoke(app, [*base, *bad, "-o", str(tmp_path / "b")])
        assert r.exit_code == 2, (bad, r.output)
