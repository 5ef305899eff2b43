"""A study streamed to Parquet holds one chunk of rows at a time (issue 22: a 10-million-variant
study must not hold its rows): the peak of traced allocations (numpy arrays and frames, every
thread) does not grow with the number of chunks."""

from __future__ import annotations

import tracemalloc

import pandas as pd

from kinprop.analysis.study import Factor, StudyTotals, read_study, run_study, sample_plan
from kinprop.builders import rssr

FACTORS = [Factor("coupler.length", 0.30, 0.32), Factor("rocker.s_i[0]", 0.34, 0.36)]
CHUNK = 200


def peak(model, n: int, out) -> tuple[int, StudyTotals]:
    """Traced peak of a streamed study of ``n`` variants; the plan (N x F numbers, which a study
    holds) is sampled before tracing starts."""
    plan = sample_plan(FACTORS, "mc", n, seed=1)
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        totals = run_study(model, plan=plan, addresses=[f.address for f in FACTORS], free=("rocker.q",),
                           chunk_size=CHUNK, output=out, collect=False)  # fmt: skip
        return tracemalloc.get_traced_memory()[1], totals
    finally:
        tracemalloc.stop()


def test_streamed_study_memory_is_bounded_per_chunk(tmp_path):
    model = rssr(theta=1.0)
    run_study(model, FACTORS, samples=CHUNK, free=("rocker.q",), chunk_size=CHUNK)  # compiles, imports
    small, _ = peak(model, 4 * CHUNK, tmp_path / "small.parquet")
    rows_small = read_study(tmp_path / "small.parquet").memory_usage(deep=True).sum()
    large, totals = peak(model, 100 * CHUNK, tmp_path / "large.parquet")
    frame = read_study(tmp_path / "large.parquet")
    rows = frame.memory_usage(deep=True).sum()
    assert totals.variants == len(frame) == 100 * CHUNK and totals.failed == int((~frame["converged"]).sum())
    # 25 times the chunks: the peak grows by less than a tenth of the rows added (holding them
    # would add all of them; measured: 0.15 MB for 2.3 MB of rows); they were never held together
    assert large - small < (rows - rows_small) / 10, (small, large, rows_small, rows)
    # the totals are the rows' own statistics
    ok = frame[frame["converged"]]
    lo, mean, hi = totals.summary("rocker.q")
    assert (lo, hi) == (ok["rocker.q"].min(), ok["rocker.q"].max())
    assert abs(mean - ok["rocker.q"].mean()) < 1e-12
    pd.testing.assert_series_equal(frame["variant"], pd.Series(range(len(frame)), name="variant"), check_dtype=False)
