"""``kinprop study --vary element:...`` and ``kinprop propagate --target ... --free element:...``
end to end: a study mixing an element point and a global hardpoint equal, row by row, to
direct propagations; a motion-ratio target met by freeing an element point with a hardpoint,
the written file re-solved independently; nonsense refused with exit 2."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_run import invoke_kinprop

import kinprop as kp
from kinprop.analysis.outputs import evaluate_outputs
from kinprop.analysis.study import read_study

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
HARDPOINTS = EXAMPLES / "double_wishbone_hardpoints.yaml"


def test_study_varies_an_element_point_with_a_hardpoint(tmp_path) -> None:
    out = tmp_path / "study"
    r = invoke_kinprop("study", HARDPOINTS, "--vary", "element:spring.point_i[z]=180:230", "--vary",
                    "hardpoint:UBJ[z]=205:225", "--samples", "3", "--out", "motion_ratio:spring", "--out",
                    "wheel_rate", "--out", "camber_gain", "-o", out, "--json")  # fmt: skip
    assert r.returncode == 0, r.stderr
    df = read_study(out)
    model = kp.load_model(HARDPOINTS)
    ubj = [-53.0352, 715.518]
    for _, row in df.iterrows():
        changes = {"element:spring.point_i[z]": row["element:spring.point_i[z]"],
                   "hardpoint:UBJ": [*ubj, row["hardpoint:UBJ[z]"]]}  # fmt: skip
        direct = evaluate_outputs(kp.propagate(model, changes).after, ["motion_ratio:spring", "wheel_rate",
                                                                       "camber_gain"])  # fmt: skip
        for name, value in direct.items():
            assert row[name] == pytest.approx(value, rel=1e-9), name


def test_target_frees_an_element_point_and_a_hardpoint(tmp_path) -> None:
    out = tmp_path / "designed.yaml"
    r = invoke_kinprop("propagate", HARDPOINTS, "--target", "motion_ratio:spring=0.5", "--target", "camber_gain=-0.02",
                    "--free", "element:spring.point_j", "--free", "hardpoint:UBJ", "-o", out)  # fmt: skip
    assert r.returncode == 0, r.stderr + r.stdout
    assert "element:spring.point_j[y] changes by" in r.stdout
    again = kp.assemble(kp.load_model(out)).after
    got = evaluate_outputs(again, ["motion_ratio:spring", "camber_gain"])
    assert got["motion_ratio:spring"] == pytest.approx(0.5, rel=1e-9)
    assert got["camber_gain"] == pytest.approx(-0.02, rel=1e-9)


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["study", "--vary", "element:sprung.point_i[z]=1:2", "-o", "{tmp}/s"], "unknown element 'sprung'"),
        (["study", "--vary", "element:spring.point_i=1:2", "-o", "{tmp}/s"], "one component"),
        (
            [
                "study",
                "--vary",
                "element:spring.point_i[z]=1:2",
                "--set",
                "element:spring.point_i=1,2,3",
                "-o",
                "{tmp}/s",
            ],
            "also given by --set",
        ),
        (["propagate", "--target", "motion_ratio:spring=0.5", "--free", "element:spring.point_q"], "point_i and"),
        (
            [
                "propagate",
                "--target",
                "motion_ratio:spring=0.5",
                "--free",
                "element:spring.point_i",
                "--set",
                "element:spring.point_i[x]=100",
            ],
            "also given by --set",
        ),
    ],
)
def test_element_point_nonsense_is_refused(tmp_path, args: list[str], says: str) -> None:
    r = invoke_kinprop(args[0], HARDPOINTS, *(a.replace("{tmp}", str(tmp_path)) for a in args[1:]))
    assert r.returncode == 2, r.stderr
    assert says in r.stderr
