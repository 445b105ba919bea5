"""Points probed on reference spheres from Python: a file or arrays, fitted
alone with a stated diameter, cross-validated and validated on a held-out
file — the command line's report bit for bit — and bad input refused by
name."""

import csv

import numpy as np
import pytest

import aacmm

from conftest import ARM


@pytest.fixture(scope="module")
def campaign(cli, tmp_path_factory):
    """An arm file with a probe ball, a simulated sphere campaign and a
    held-out one of the same true arm."""
    root = tmp_path_factory.mktemp("spheres")
    text = pathlib_read(ARM).replace("[probe]\n", "[probe]\nball_diameter_mm = 6.0\n")
    arm = root / "arm.toml"
    arm.write_text(text)
    noise = ["--encoder-noise", "0.005", "--probe-noise", "0.01"]
    cli("simulate", "--arm", arm, "--errors", "paper", "--spheres", "4", *noise,
        "--seed", "3", "--out", root / "sim")
    cli("simulate", "--arm", arm, "--true", root / "sim" / "true_arm.toml",
        "--spheres", "2", *noise, "--seed", "8", "--out", root / "held")
    return arm, root / "sim" / "spheres.csv", root / "held" / "spheres.csv"


def pathlib_read(path):
    with open(path) as f:
        return f.read()


def arrays(path):
    """The labels and readings (rad) of a sphere-surface file."""
    with open(path) as f:
        rows = list(csv.reader(f))[1:]
    labels = [r[0] for r in rows]
    q = np.radians(np.array([[float(v) for v in r[1:7]] for r in rows]))
    return labels, q


NOISE = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)


def test_spheres_alone_equal_the_cli_files(cli, campaign, tmp_path):
    arm_file, spheres, held = campaign
    out = tmp_path / "cli"
    cli("calibrate", "--arm", arm_file, "--spheres", spheres, "--sphere-diameter", "25.4",
        "--encoder-noise", "0.005", "--probe-noise", "0.01", "--cross-validate", "3",
        "--validate-spheres", held, "--method", "lm", "--threads", "1", "--out", out)
    arm = aacmm.Arm.from_file(str(arm_file))
    cal = aacmm.calibrate(
        arm, spheres=str(spheres), sphere_diameter=25.4, noise=NOISE, method="lm",
        cross_validate=3, validate_spheres=held, threads=1,
    )
    assert cal.to_json() == (out / "calibration.json").read_text()
    report = cal.report
    assert report["spheres"]["stated_diameter"] == 25.4
    folds = report["validation"]["cross_validation"]["folds"]
    assert [f["terms"][0]["term"] for f in folds] == ["spheres"] * 3
    held_out = report["validation"]["held_out_spheres"]
    assert held_out["after"]["count"] == 50
    assert held_out["after"]["rms"] < 0.2 * held_out["before"]["rms"]


def test_arrays_give_the_file_s_fit(campaign):
    arm_file, spheres, held = campaign
    arm = aacmm.Arm.from_file(str(arm_file))
    common = dict(sphere_diameter=25.4, noise=NOISE, method="lm", threads=1)
    from_file = aacmm.calibrate(arm, spheres=spheres, **common)
    from_arrays = aacmm.calibrate(arm, spheres=arrays(spheres), validate_spheres=arrays(held),
                                  **common)
    np.testing.assert_allclose(from_arrays.params, from_file.params, rtol=0, atol=1e-9)
    report = from_arrays.report
    assert report["spheres"]["file"] == "<arrays>"
    assert report["validation"]["held_out_spheres"]["file"] == "<arrays>"
    # Without a stated diameter each sphere's is fitted.
    fitted = aacmm.calibrate(arm, spheres=arrays(spheres), noise=NOISE, method="lm", threads=1)
    assert fitted.report["spheres"]["stated_diameter"] is None


def test_bad_spheres_are_refused_by_name(campaign):
    arm_file, spheres, _ = campaign
    arm = aacmm.Arm.from_file(str(arm_file))
    labels, q = arrays(spheres)
    with pytest.raises(ValueError, match="data: give a DataSet, spheres or both"):
        aacmm.calibrate(arm)
    with pytest.raises(ValueError, match="spheres: a sphere-surface file's path, or a pair"):
        aacmm.calibrate(arm, spheres=3)
    with pytest.raises(ValueError, match="spheres: 99 labels for 100 rows"):
        aacmm.calibrate(arm, spheres=(labels[:99], q))
    with pytest.raises(ValueError, match=r"spheres\[1\]: shape"):
        aacmm.calibrate(arm, spheres=(labels, q[:, :5]))
    # Three points of a sphere: the library's refusal, by row and field.
    few = [0, 1, 2] + list(range(25, 100))
    with pytest.raises(aacmm.InputError, match=r"<arrays>:1: field `sphere`.*3 points"):
        aacmm.calibrate(arm, spheres=([labels[i] for i in few], q[few]))
    with pytest.raises(ValueError, match="sphere_diameter"):
        aacmm.calibrate(arm, spheres=spheres, sphere_diameter=0.0254)
    bad = q.copy()
    bad[4, 2] = np.nan
    with pytest.raises(ValueError, match="spheres: row 5: q3 is not a finite number"):
        aacmm.calibrate(arm, spheres=(labels, bad))


def test_a_tool_column_from_arrays_fits_that_tool(campaign, tmp_path):
    """`(labels, q, tools)`: every point probed with a `[[tool]]` at the
    probe's offset and ball gives the probe's fit, the offset reported as
    the tool's (`Calibration.tools`); a tool the arm does not know, and a
    sphere probed by two tools, are refused by row and field."""
    arm_file, spheres, _ = campaign
    text = pathlib_read(arm_file)
    plain = aacmm.Arm.from_file(str(arm_file))
    probe = ", ".join(repr(float(v)) for v in plain.params[-3:])
    tooled = tmp_path / "tooled.toml"
    tooled.write_text(
        text + f'\n[[tool]]\nname = "long"\noffset_mm = [{probe}]\nball_diameter_mm = 6.0\n'
    )
    arm = aacmm.Arm.from_file(str(tooled))
    labels, q = arrays(spheres)
    common = dict(sphere_diameter=25.4, noise=NOISE, method="lm", threads=1)
    by_probe = aacmm.calibrate(arm, spheres=(labels, q), **common)
    by_tool = aacmm.calibrate(arm, spheres=(labels, q, "long"), **common)
    assert by_probe.tools == {}
    assert list(by_tool.tools) == ["long"]
    # The same fit: the points where each puts the ball's centre. (The
    # parameters held differ: the probe's Bx, By are redundant with the last
    # link's, the tool's offset is fitted whole and the link held instead.)
    seen = by_tool.params.copy()
    seen[-3:] = by_tool.tools["long"]["offset_mm"]
    as_tool = aacmm.Arm.from_params(arm.joints, seen)
    np.testing.assert_allclose(as_tool.positions(q), by_probe.arm.positions(q), rtol=0, atol=1e-5)
    assert all(by_tool.fixed[b].startswith("unseen") for b in ("Bx", "By", "Bz")), by_tool.fixed
    with pytest.raises(aacmm.InputError, match=r"<arrays>:1: field `tool`: `short`"):
        aacmm.calibrate(arm, spheres=(labels, q, "short"), **common)
    two = ["long" if i == 3 else "" for i in range(len(labels))]
    with pytest.raises(aacmm.InputError, match=r"<arrays>:4: field `tool`.*probed by `probe`"):
        aacmm.calibrate(arm, spheres=(labels, q, two), **common)
    with pytest.raises(ValueError, match=r"spheres\[2\]: 2 names for 100 rows"):
        aacmm.calibrate(arm, spheres=(labels, q, ["long", "long"]), **common)
