"""Issue 43 from Python: the first reason of a refusal names the true cause,
no refusal recommends an option in use, every data path checks the lengths'
unit, a χ² note says it is one, and write() keeps earlier results."""

import pytest

import aacmm
from conftest import ARM, LENGTHS, POSES, REPO, read_lengths, read_poses

NOISE = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)


def test_another_robots_touches_disagree_with_the_arm_first(arm):
    """Case 1: the Kinova's touches (radians) with the paper's arm: the first
    reason is that data and arm disagree, not the solver's start budget."""
    kinova = aacmm.DataSet.from_files("examples/mukca/kinova-1/poses.csv", angle_unit="rad")
    cal = aacmm.calibrate(arm, kinova)
    reasons = cal.report["verdict"]["reasons"]
    assert not cal.successful
    assert reasons[0].startswith("the data and the arm disagree: none of the "), reasons
    assert all("more starts" not in r for r in reasons), reasons
    assert "Verdict: NOT usable — the data and the arm disagree" in cal.text()


def test_a_mislabelled_touch_with_robust_under_global_is_usable(arm):
    """Case 2: one mislabelled touch (line 18, S2 labelled S1), robust under
    the default global method: weighed out, reported, usable."""
    labels, q = read_poses()
    labels = list(labels)
    labels[16] = "S1"
    data = aacmm.DataSet(labels, q, read_lengths(), angle_unit="deg")
    for loss in ("huber", "cauchy"):
        cal = aacmm.calibrate(arm, data, noise=NOISE, robust=loss)
        assert cal.successful, cal.report["verdict"]
        assert cal.report["calibration"]["solver"]["stop"]["global"]["search"] == "robust_floor"
        low = [w["at"] for w in cal.report["calibration"]["robust"]["weights"] if w["weight"] < 0.25]
        assert low == ["<arrays>:17"]
        assert all("--robust" not in n for n in cal.report["verdict"]["notes"])


def test_lengths_in_metres_are_refused_by_evaluate_identify_and_calibrate(arm, tmp_path):
    """Case 3: every path that reads reference lengths checks their unit,
    naming the lengths file."""
    metres = tmp_path / "lengths-m.csv"
    metres.write_text(
        "point_a,point_b,distance\n"
        + "".join(f"{a},{b},{d / 1000}\n" for a, b, d in read_lengths())
    )
    data = aacmm.DataSet.from_files(POSES, str(metres))
    message = rf"{metres}: the reference lengths are 1.000e-3 times the nominal arm's"
    for call in (
        lambda: aacmm.evaluate(arm, data),
        lambda: aacmm.identify(arm, data, noise=NOISE),
        lambda: aacmm.calibrate(arm, data, noise=NOISE),
    ):
        with pytest.raises(aacmm.CalibrationError, match=message):
            call()


def test_an_arm_file_in_the_wrong_unit_is_named(tmp_path, data):
    """Case 4: millimetres declared as metres: the arm file is blamed (the
    warning and the error), not the lengths file."""
    wrong = tmp_path / "arm-m.toml"
    wrong.write_text((REPO / ARM).read_text().replace('length_unit = "mm"', 'length_unit = "m"'))
    with pytest.warns(UserWarning, match="lengths declared in metres"):
        arm = aacmm.Arm.from_file(str(wrong))
    for call in (
        lambda: aacmm.evaluate(arm, data),
        lambda: aacmm.calibrate(arm, data, noise=NOISE),
    ):
        with pytest.raises(aacmm.CalibrationError, match=rf"^{wrong}: the arm file's lengths"):
            call()


def test_write_keeps_any_earlier_results(arm, data, tmp_path):
    """Case 6: a campaign is not written into a calibration's directory, nor
    a calibration into a campaign's, without force=True."""
    cal = aacmm.calibrate(arm, data, noise=NOISE)
    campaign = aacmm.simulate(arm, poses=4, seed=1, sockets=3)
    cal.write(tmp_path / "cal")
    with pytest.raises(OSError, match=r"earlier result \(calibrated.toml\).*force=True"):
        campaign.write(tmp_path / "cal")
    assert not (tmp_path / "cal" / "poses.csv").exists()
    campaign.write(tmp_path / "campaign")
    with pytest.raises(OSError, match=r"earlier result \(poses.csv\).*force=True"):
        cal.write(tmp_path / "campaign")
    campaign.write(tmp_path / "cal", force=True)
    assert (tmp_path / "cal" / "calibrated.toml").exists()


def test_a_chi_square_note_says_it_is_not_a_refusal(arm, data):
    """Case 8: a tight prior's χ² below 0.001 is a note, said so in its
    sentence beside "Verdict: usable"."""
    cal = aacmm.calibrate(arm, data, noise=NOISE, prior="length=0.5mm,angle=0.1deg", method="lm")
    assert cal.successful
    notes = cal.report["verdict"]["notes"]
    assert any("so a note, not a refusal: the fit is usable); it suggests" in n for n in notes), notes
    assert "Verdict: usable\n  note: χ² = " in cal.text()
