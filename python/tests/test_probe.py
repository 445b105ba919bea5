"""Probe qualification from Python (``aacmm.qualify_probe``): the command
line's ``aacmm probe`` — the same qualified arm from a file or from arrays —
a loose stylus refused in this module's words, and a probe the arm does not
know named."""

import csv

import numpy as np
import pytest

import aacmm

from conftest import ARM

NOISE = aacmm.Noise(encoder_deg=0.001, probe_mm=0.005)


@pytest.fixture(scope="module")
def points(cli, tmp_path_factory):
    """An arm file with a probe ball, one sphere probed by that very arm
    (its geometry is the truth, as a qualification assumes), and the same
    sphere probed by a loose stylus (ten times the seating noise)."""
    root = tmp_path_factory.mktemp("probe")
    with open(ARM) as f:
        text = f.read().replace("[probe]\n", "[probe]\nball_diameter_mm = 6.0\n")
    arm = root / "arm.toml"
    arm.write_text(text)
    for name, probe in [("good", "0.005"), ("loose", "0.05")]:
        cli("simulate", "--arm", arm, "--true", arm, "--spheres", "1", "--encoder-noise",
            "0.001", "--probe-noise", probe, "--seed", "5", "--out", root / name)
    return arm, root / "good" / "spheres.csv", root / "loose" / "spheres.csv"


def test_a_probe_qualifies_as_the_command_line_qualifies_it(cli, points, tmp_path):
    arm_file, good, _ = points
    out = tmp_path / "qualified.toml"
    cli("probe", "--arm", arm_file, "--spheres", good, "--sphere-diameter", "25.4",
        "--encoder-noise", "0.001", "--probe-noise", "0.005", "--out", out)
    arm = aacmm.Arm.from_file(str(arm_file))
    q, qualified = aacmm.qualify_probe(arm, str(good), 25.4, noise=NOISE)
    assert q["usable"] and q["refusals"] == []
    assert qualified is not None
    assert qualified.to_toml() == aacmm.Arm.from_file(str(out)).to_toml()
    assert abs(q["ball_diameter_mm"] - 6.0) < 4 * q["ball_sigma_mm"] + 1e-9
    assert not np.array_equal(qualified.params, arm.params)

    # The same rows as arrays (readings in rad): the same qualification.
    with open(good) as f:
        rows = list(csv.reader(f))[1:]
    labels = [r[0] for r in rows]
    q_rad = np.radians(np.array([[float(v) for v in r[1:7]] for r in rows]))
    q2, qualified2 = aacmm.qualify_probe(arm, (labels, q_rad), 25.4, noise=NOISE)
    assert q2["offset"] == q["offset"] and q2["ball_diameter_mm"] == q["ball_diameter_mm"]
    assert qualified2.to_toml() == qualified.to_toml()


def test_a_loose_stylus_is_refused_in_pythons_words(points):
    arm_file, _, loose = points
    arm = aacmm.Arm.from_file(str(arm_file))
    q, qualified = aacmm.qualify_probe(arm, str(loose), 25.4, noise=NOISE)
    assert not q["usable"] and qualified is None
    text = " ".join(q["refusals"])
    assert "χ²" in text or "outlying" in text, text
    assert "--" not in text, text


def test_a_probe_the_arm_does_not_know_is_named(points):
    arm_file, good, _ = points
    arm = aacmm.Arm.from_file(str(arm_file))
    with pytest.raises(ValueError) as e:
        aacmm.qualify_probe(arm, str(good), 25.4, tool="short")
    assert "tool = short: the arm has no such tool" in str(e.value)
    assert "`probe`" in str(e.value)
    with pytest.raises(ValueError) as e:
        aacmm.qualify_probe(arm, str(good), 0.0254)
    assert "mm" in str(e.value)
