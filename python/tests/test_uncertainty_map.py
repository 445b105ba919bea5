"""``Calibration.uncertainty_map``: the predicted position uncertainty over a
sampled workspace, the same numbers as calibration.json's ``/uncertainty_map``
(and as the command line's), with the figure's points as numpy arrays; the
report written beside it holds its figure."""

import json

import numpy as np
import pytest

import aacmm
from conftest import ARM, LENGTHS, POSES


@pytest.fixture(scope="module")
def cal():
    arm = aacmm.Arm.from_file(ARM)
    data = aacmm.DataSet.from_files(POSES, LENGTHS)
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
    return aacmm.calibrate(arm, data, method="lm", noise=noise)


def test_the_map_is_the_reports_number_for_number(cal):
    m = cal.uncertainty_map
    j = cal.report["uncertainty_map"]
    assert m is not None
    for key in ("coverage", "k_isotropic", "workspace", "poses", "rms_mm", "median_mm", "max_mm"):
        assert m[key] == j[key], key
    assert type(m["poses"]) is int
    # 95 %, and the radius of an isotropic 3-D error: sqrt(chi2_3(0.95)).
    assert m["coverage"] == 0.95
    assert m["k_isotropic"] == pytest.approx(2.7955, abs=1e-4)
    assert m["regions"] == j["regions"]
    assert sum(r["poses"] for r in m["regions"]) == m["poses"]
    for r in m["regions"]:
        assert r["reach_from_mm"] < r["reach_to_mm"]
        assert r["rms_mm"] <= r["max_mm"] <= m["max_mm"]

    points = m["points"]
    assert set(points) == {"reach_mm", "height_mm", "radius_mm"}
    for key, column in points.items():
        assert isinstance(column, np.ndarray) and column.dtype == np.float64, key
        assert np.array_equal(column, [p[key] for p in j["points"]]), key
    assert 0 < len(points["radius_mm"]) <= m["poses"]
    assert (points["radius_mm"] > 0).all()
    assert points["radius_mm"].max() <= m["max_mm"]


def test_the_command_line_writes_the_same_map_and_its_figure(cli, cal, tmp_path):
    out = tmp_path / "cli"
    cli(
        "calibrate", "--arm", ARM, "--data", POSES, "--lengths", LENGTHS,
        "--encoder-noise", "0.005", "--probe-noise", "0.01", "--method", "lm", "--out", out,
    )
    theirs = json.loads((out / "calibration.json").read_text())["uncertainty_map"]
    m = cal.uncertainty_map
    assert theirs["rms_mm"] == m["rms_mm"] and theirs["regions"] == m["regions"]
    ours = tmp_path / "ours"
    names = [p.name for p in cal.write(ours)]
    assert "uncertainty-map.svg" in names
    assert (ours / "uncertainty-map.svg").read_text() == (out / "uncertainty-map.svg").read_text()
    html = (ours / "report.html").read_text()
    assert 'id="uncertainty-map"' in html
    assert "2.80 σ for an isotropic 3-D error, not 2 σ" in html


def test_the_maps_in_frames_and_at_tools_are_the_reports():
    """The UR5 tracker campaign: its one instrument frame's map (the radii
    with the frame's registration) number for number as the report's, and
    no map at a tool point (no [[tool]] was fitted)."""
    arm = aacmm.Arm.from_file("examples/ur5-tracker/arm.toml")
    data = aacmm.DataSet.from_files(positions="examples/ur5-tracker/positions-grid.csv")
    ur5 = aacmm.calibrate(arm, data, method="lm")
    maps = ur5.uncertainty_maps_in_frames
    j = ur5.report["uncertainty_maps_in_frames"]
    assert len(maps) == len(j) == 1
    assert maps[0]["frame"] == j[0]["frame"] == "instrument"
    for key in ("coverage", "workspace", "poses", "rms_mm", "median_mm", "max_mm", "regions"):
        assert maps[0][key] == j[0][key], key
    assert np.array_equal(maps[0]["points"]["radius_mm"], [p["radius_mm"] for p in j[0]["points"]])
    # Another map than the base frame's: the instrument sees the positions
    # through the fitted frame, whose registration it includes.
    assert 0 < maps[0]["rms_mm"] != ur5.uncertainty_map["rms_mm"]
    assert ur5.uncertainty_maps_at_tools == [] and "uncertainty_maps_at_tools" not in ur5.report
