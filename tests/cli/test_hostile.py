"""Hostile values and option combinations: every run ends, within memory, with a clear exit
code (issue 11, item 2). The commands run in a fresh process limited to 4 GB of address space,
one after the other, each under a timeout (:func:`cli_run.run_kinprop_cases`: one interpreter
for all of them); before the fix a RuntimeWarning re-emission loop in cli/continuation.py made
the first two run until the machine ran out of memory, and a 10^15-variant grid was allocated
before anything was checked.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest
from cli_run import one_error_line, run_kinprop_cases

BIG = 10**12

#: (arguments, allowed exit codes, text the error line must contain)
CASES = [
    # overflow inside the solver: a diagnosis and exit 1, never an endless warning loop
    # absurd values (beyond 1e6 x the model's length scale) are rejected before any work: exit 2
    (["propagate", "double_wishbone.yaml", "--set", "TR.length=1e30"], {2}, None),
    (["propagate", "double_wishbone.yaml", "--set", "TR.length=1e308"], {2}, None),
    (["propagate", "fourbar.yaml", "--set", "B.s_i[0]=1e200"], {2}, None),
    (["propagate", "slider_crank.yaml", "--set", "J12.s_j=1e308,1e308,1e308"], {2}, None),
    (["propagate", "fourbar.yaml", "--set", "O2.q=1e308"], {2}, None),
    (["sweep", "fourbar.yaml", "--drive", "O2=0:1e300:3", "-q"], {1, 2}, None),
    (["tolerance", "fourbar.yaml", "--tolerance", "B.s_i[0]=1e300", "--of", "O4.q"], {0, 1}, None),
    # sizes refused up front, with the count
    (
        ["study", "mcpherson.yaml", "-o", "{tmp}/s", "--method", "grid", "--samples", "1000"]
        + [
            x
            for a in (
                "RS.length=0.2:0.21",
                "TD.s_j[1]=0.15:0.16",
                "ST.s_i[0]=0.4:0.5",
                "ST.s_i[1]=1:1.1",
                "ST.s_i[2]=0:0.1",
            )
            for x in ("--vary", a)
        ],
        {2},
        "1000^5 = 1e+15 variants",
    ),
    (
        ["study", "fourbar.yaml", "-o", "{tmp}/s", "--vary", "B.s_i[0]=0.39:0.41", "--samples", str(BIG)],
        {2},
        "--samples",
    ),
    (
        ["study", "fourbar.yaml", "-o", "{tmp}/s", "--vary", "B.s_i[0]=0.39:0.41", "--chunk-size", "0"],
        {2},
        "--chunk-size",
    ),
    (["sweep", "fourbar.yaml", "--drive", f"O2=0:360:{BIG}"], {2}, "steps; the limit is"),
    (["tolerance", "fourbar.yaml", "--tolerance", "B.s_i[0]=5e-4", "--of", "O4.q", "--mc", str(BIG)], {2}, "--mc"),
    (["tolerance", "fourbar.yaml", "--tolerance", "B.s_i[0]=5e-4", "--of", "O4.q", "--mc", "-3"], {2}, "--mc -3"),
    (["assemble", "fourbar.yaml", "--max-iter", str(BIG)], {2}, "--max-iter"),
    # values that are not numbers a solver can use
    (["propagate", "fourbar.yaml", "--set", "O2.q=nan"], {2}, "finite"),
    (["propagate", "fourbar.yaml", "--set", "O2.q=-inf"], {2}, "finite"),
    (["assemble", "fourbar.yaml", "--tol", "nan"], {2}, "--tol nan"),
    (["assemble", "fourbar.yaml", "--tol", "-1"], {2}, "--tol -1"),
    (["assemble", "fourbar.yaml", "--tol", "0"], {2}, "--tol 0"),
    (["assemble", "fourbar.yaml", "--max-iter", "-5"], {2}, "--max-iter -5"),
    (["propagate", "fourbar.yaml", "--set", "O2.q=70", "--weight", "q=-1"], {2}, "--weight"),
    (["propagate", "fourbar.yaml", "--set", "O2.q=70", "--weight", "q=inf"], {2}, "--weight"),
    (["sensitivity", "fourbar.yaml", "--wrt", "B.s_i", "--tol", "inf"], {2}, "--tol inf"),
    (["sweep", "fourbar.yaml", "--drive", "O2=0:nan:3"], {2}, "--drive"),
    (["study", "fourbar.yaml", "-o", "{tmp}/s", "--vary", "B.s_i[0]=1:nan"], {2}, "--vary"),
]


@pytest.fixture(scope="module")
def outcomes(examples, tmp_path_factory) -> list[tuple[list[str], subprocess.CompletedProcess[str], Path]]:
    """Every case once, all in one bounded process; case k writes under its own directory."""
    base = tmp_path_factory.mktemp("hostile")
    argvs, tmps = [], [base / str(k) for k in range(len(CASES))]
    for (args, _, _), tmp in zip(CASES, tmps, strict=True):
        tmp.mkdir()
        argv = [a.format(tmp=tmp) for a in args]
        argv[1] = str(examples / argv[1])
        argvs.append(argv)
    return list(zip(argvs, run_kinprop_cases(argvs), tmps, strict=True))


@pytest.mark.parametrize("k", range(len(CASES)), ids=[" ".join(c[0][:4])[:60] for c in CASES])
def test_hostile_input_is_bounded(k, outcomes) -> None:
    (_, codes, needle), (argv, p, tmp) = CASES[k], outcomes[k]
    assert p.returncode in codes, (argv, p.returncode, p.stdout[-1500:], p.stderr[-1500:])
    assert "Traceback" not in p.stderr and "MemoryError" not in p.stderr, p.stderr[-3000:]
    if needle is not None:
        assert needle in one_error_line(p)
    assert not (tmp / "s").exists()  # a refused study creates nothing
