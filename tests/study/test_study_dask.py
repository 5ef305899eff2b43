"""Studies on a Dask distributed cluster (a LocalCluster of two worker processes started here)."""

from __future__ import annotations

import pandas as pd
import pytest
from typer.testing import CliRunner

from kinprop.analysis.study import Factor, read_study, run_study
from kinprop.builders import rssr
from kinprop.cli import app

distributed = pytest.importorskip("distributed")

FACTORS = [Factor("coupler.length", 0.30, 0.32), Factor("rocker.s_i[0]", 0.34, 0.36)]


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=40
    ) as c:
        yield c


def test_dask_study_matches_local_and_resumes(cluster, tmp_path):
    model = rssr(theta=1.0)
    kw = {"method": "lhs", "samples": 30, "seed": 5, "free": ("rocker.q",), "chunk_size": 7}
    local = run_study(model, FACTORS, **kw)
    out = tmp_path / "dask.parquet"
    remote = run_study(model, FACTORS, **kw, output=out, scheduler=cluster.scheduler_address)
    pd.testing.assert_frame_equal(remote, local)
    for p in sorted(out.glob("part-*.parquet"))[1:3]:
        p.unlink()
    computed: list[int] = []
    again = run_study(model, FACTORS, **kw, output=out, resume=True, scheduler=cluster.scheduler_address,
                      on_chunk=computed.append)  # fmt: skip
    assert sorted(computed) == [1, 2]
    pd.testing.assert_frame_equal(again, local)


def test_cli_study_on_cluster(cluster, tmp_path, rssr_file):
    out = tmp_path / "cli.parquet"
    args = ["study", str(rssr_file), "--vary", "coupler.length=0.30:0.32", "--samples", "3", "--method", "grid",
            "--free", "rocker.q", "--chunk-size", "1", "-o", str(out)]  # fmt: skip
    r = CliRunner().invoke(app, [*args, "--scheduler", cluster.scheduler_address])
    assert r.exit_code == 0, r.output
    df = read_study(out)
    assert len(df) == 3 and df["converged"].all()
