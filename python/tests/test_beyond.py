"""Models beyond geometry (joint compliance, encoder harmonics, backlash,
thermal expansion, drift) through ``calibrate``'s keyword arguments: the command
line's report for the same flags, the fitted values in ``auxiliary`` and
``physics``, and every spec or input the library refuses named by its
argument."""

import pytest

import aacmm
from conftest import ARM, POSES

UR5 = "examples/ur5-tracker/arm.toml"
GRID = "examples/ur5-tracker/positions-grid.csv"


@pytest.fixture(scope="module")
def ur5():
    return aacmm.Arm.from_file(UR5)


@pytest.fixture(scope="module")
def grid():
    return aacmm.DataSet.from_files(positions=GRID)


def test_compliance_gives_the_command_lines_report(cli, ur5, grid, tmp_path):
    """``compliance="2,3"`` is ``--compliance 2,3``: calibration.json byte
    for byte; the compliances are the first auxiliary columns, fitted and
    seen by the data, and the physics holds them in rad/(N·m)."""
    out = tmp_path / "cli"
    cli(
        "calibrate", "--arm", UR5, "--positions", GRID, "--compliance", "2,3",
        "--method", "lm", "--out", out,
    )
    cal = aacmm.calibrate(ur5, grid, method="lm", compliance="2,3")
    assert cal.to_json() == (out / "calibration.json").read_text()

    aux = cal.auxiliary
    assert list(aux)[:3] == ["compliance2", "compliance3", "instrument.rx"]
    assert len(aux) == 2 + 6
    assert [dict(name=k, **v) for k, v in aux.items()] == [
        {k: column.get(k) for k in ("name", "unit", "start", "calibrated", "sigma", "sigma_of", "fixed")}
        for column in cal.report["calibration"]["auxiliary"]
    ]
    physics = cal.physics
    assert physics == cal.report["calibration"]["physics"]
    assert physics["compliance"][0] is None and physics["compliance"][3:] == [None] * 3
    for j in (2, 3):
        c = aux[f"compliance{j}"]
        assert c["unit"] == "µrad/(N·m)" and c["start"] == 0.0 and c["fixed"] is None
        assert abs(c["calibrated"]) > 5 * c["sigma"], c
        assert physics["compliance"][j - 1] == pytest.approx(c["calibrated"] * 1e-6, rel=1e-12)
    assert "drift_mm_per_h" not in physics

    # Without the option: no correction column, and no physics at the fit
    # (masses alone correct nothing).
    geometric = aacmm.calibrate(ur5, grid, method="lm")
    assert list(geometric.auxiliary) == list(aux)[2:]
    assert geometric.physics is None


def test_a_held_correction_says_why(ur5, grid):
    """Joint 1's axis is vertical: gravity does not load it, so its
    compliance moves no residual and is held at its start, with the reason."""
    cal = aacmm.calibrate(ur5, grid, method="lm", compliance="1")
    c = cal.auxiliary["compliance1"]
    assert c["sigma"] is None and c["calibrated"] == c["start"] == 0.0
    assert "these data do not see it" in c["fixed"]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"compliance": "0"}, "compliance = 0: a joint is a number from 1"),
        ({"compliance": "2,2"}, "compliance = 2: joint listed twice"),
        ({"compliance": "7"}, "compliance = 7: joint 7: the arm has 6 joints"),
        ({"harmonics": "2:"}, "harmonics = 2:: an order is a whole number from 1 to 16"),
        ({"harmonics": "2"}, "harmonics = 2: expected JOINT:ORDERS"),
        ({"harmonics": "2:3-1"}, "harmonics = 2:3-1: empty order range"),
        ({"backlash": "2,2"}, "backlash = 2: joint listed twice"),
        ({"backlash": "7"}, "backlash = 7: joint 7: the arm has 6 joints"),
        ({"thermal": True}, "thermal = on: thermal expansion needs the temperature of every pose"),
        ({"drift": True}, "drift = on: a drift needs the time of every pose"),
    ],
)
def test_a_bad_spec_or_missing_input_names_the_argument(ur5, grid, kwargs, message):
    with pytest.raises(ValueError) as e:
        aacmm.calibrate(ur5, grid, method="lm", **kwargs)
    assert str(e.value).startswith(message), str(e.value)


def test_a_backlash_is_fitted_or_held_and_named(cli, ur5, grid, tmp_path):
    """``backlash="2,3"`` is ``--backlash 2,3``: calibration.json byte for
    byte. The grid leans the UR5 one way only: the shoulder's torque keeps
    its sign, so its play is its zero offset, held with why; the elbow's is
    a column of its own, in degrees, with its σ, and the physics has it."""
    out = tmp_path / "cli"
    cli(
        "calibrate", "--arm", UR5, "--positions", GRID, "--backlash", "2,3",
        "--method", "lm", "--out", out,
    )
    cal = aacmm.calibrate(ur5, grid, method="lm", backlash="2,3")
    assert cal.to_json() == (out / "calibration.json").read_text()
    held = cal.auxiliary["backlash2"]
    assert held["sigma"] is None and "not separable" in held["fixed"]
    b = cal.auxiliary["backlash3"]
    assert b["unit"] == "deg" and b["fixed"] is None and b["sigma"] > 0
    assert cal.physics["backlash"][2] is not None


def test_a_compliance_needs_masses():
    """The paper's arm file states no masses: nothing loads the joints."""
    arm = aacmm.Arm.from_file(ARM)
    data = aacmm.DataSet.from_files(POSES)
    with pytest.raises(ValueError, match=r"^compliance = 2,3: no mass loads the joints"):
        aacmm.calibrate(arm, data, method="lm", compliance="2,3")
