"""A study's bookkeeping (issue 19 item 7): the summary lists the requested outputs and
each column once; the parts name a global factor as the user did; the manifest records the
method and seed that sampled it. Truth: Latin hypercube stratification (one sample per
stratum) and the hardpoint model's s' = global point for a joint on the fixed chassis.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

from kinprop.cli import app

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
N = 20


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("st") / "st"
    args = ["study", str(EXAMPLES / "double_wishbone_hardpoints.yaml"), "--vary", "hardpoint:UCA.i[z]=215:225",
            "--method", "lhs", "--seed", "1", "--samples", str(N), "--out", "camber", "--out", "toe", "-o", str(out),
            "--engine", "reference"]  # fmt: skip
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    return out, r.stdout


def test_summary_lists_the_outputs_and_each_column_once(study):
    _, text = study
    rows = [ln.split("│")[1].strip() for ln in text.splitlines() if ln.startswith("│")]
    assert len(rows) == len(set(rows))
    assert rows[:5] == ["hardpoint:UCA.i[z]", "camber", "toe", "iterations", "residual"]


def test_parts_and_manifest_name_the_factor_as_given(study):
    out, _ = study
    part = pd.read_parquet(next(out.glob("part-*.parquet")))
    z = part["hardpoint:UCA.i[z]"].to_numpy()
    np.testing.assert_array_equal(z, part["UCA.s_i[2]"].to_numpy())  # chassis frame = global
    strata = np.floor((z - 215.0) / 10.0 * N).astype(int)
    assert sorted(strata) == list(range(N))  # Latin hypercube: one sample per stratum
    manifest = json.loads((out / "_study.json").read_text())
    assert (manifest["method"], manifest["seed"], manifest["samples"]) == ("lhs", 1, N)
    assert manifest["factors"] == ["hardpoint:UCA.i[z]"]
