"""Studies on a Dask distributed cluster (a LocalCluster of two worker processes started here)."""

from __future__ import annotations

import numpy as np
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


def test_scheduler_and_workers_as_separate_processes(tmp_path, rssr_file):
    """The multi-machine set-up of docs/performance.md on one machine: ``dask scheduler`` and two
    ``dask worker`` processes started from the shell, ``kinprop study --scheduler`` in a third
    process; the rows equal the local study's."""
    import json
    import os
    import subprocess
    import sys
    import time
    from pathlib import Path

    bindir = Path(sys.executable).parent
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)}
    info = tmp_path / "scheduler.json"

    def spawn(args: list[str], cwd: Path) -> subprocess.Popen:
        quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
        return subprocess.Popen([str(bindir / "dask"), *args, "--no-dashboard"], env=env, cwd=cwd, **quiet)

    procs = [spawn(["scheduler", "--port", "0", "--scheduler-file", str(info)], tmp_path)]
    try:
        for _ in range(600):
            if info.exists() and info.stat().st_size:
                break
            time.sleep(0.1)
        address = json.loads(info.read_text())["address"]
        for k in range(2):
            work = tmp_path / f"worker{k}"
            work.mkdir()
            procs.append(spawn(["worker", address, "--nthreads", "1"], work))
        with distributed.Client(address, timeout="60s") as client:
            client.wait_for_workers(2, timeout=120)
        out = tmp_path / "remote.parquet"
        args = ["study", str(rssr_file), "--vary", "coupler.length=0.30:0.32", "--vary", "rocker.s_i[0]=0.34:0.36",
                "--samples", "40", "--seed", "3", "--free", "rocker.q", "--chunk-size", "7"]  # fmt: skip
        run = subprocess.run([sys.executable, "-m", "kinprop", *args, "-o", str(out), "--scheduler", address, "--json"],
                             env=env, capture_output=True, text=True, timeout=600)  # fmt: skip
        assert run.returncode == 0, run.stderr
        assert json.loads(run.stdout)["variants"] == 40
    finally:
        for p in procs[::-1]:
            p.terminate()
        for p in procs:
            p.wait(timeout=60)
    local = tmp_path / "local.parquet"
    assert CliRunner().invoke(app, [*args, "-o", str(local)]).exit_code == 0
    pd.testing.assert_frame_equal(read_study(out), read_study(local))


def test_worker_writes_its_part_only_where_it_sees_the_study(tmp_path):
    """A worker that sees the study's directory (its manifest, this plan) writes the chunk's part
    and returns only its totals; one that does not (another machine) returns the rows."""
    import json

    from kinprop.analysis.study import MANIFEST, StudySpec, StudyTotals, _model_payload, evaluate_payload

    model = rssr(theta=1.0)
    spec = StudySpec(addresses=["coupler.length"], free=["rocker.q"], plan_hash="abc", model_hash="m")
    values = [[0.30], [0.31]]
    elsewhere = evaluate_payload(_model_payload(model), spec, np.array(values), 0, (str(tmp_path), 0))
    assert isinstance(elsewhere, pd.DataFrame) and not list(tmp_path.iterdir())
    (tmp_path / MANIFEST).write_text(json.dumps({"plan_hash": "abc"}))
    here = evaluate_payload(_model_payload(model), spec, np.array(values), 0, (str(tmp_path), 0))
    assert isinstance(here, StudyTotals) and (here.variants, here.failed) == (2, 0)
    pd.testing.assert_frame_equal(read_study(tmp_path), elsewhere)
