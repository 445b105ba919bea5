"""Chains with prismatic joints: a robot on a track (P+6R) through the
Python front end, against the command line."""

import numpy as np
import pytest

import aacmm

TRACK = "examples/track-6r.toml"


def track_readings():
    rng = np.random.default_rng(3)
    q = rng.uniform(-170.0, 170.0, size=(50, 7))
    q[:, 0] = rng.uniform(0.0, 1500.0, size=50)  # the carriage, mm
    return q


def test_a_track_arm_reads_its_slide_in_mm_whatever_the_angle_unit(cli, tmp_path):
    arm = aacmm.Arm.from_file(TRACK)
    assert arm.joint_types == "PRRRRRR" and arm.joints == 7
    q = track_readings()
    in_rad = q.copy()
    in_rad[:, 1:] = np.radians(q[:, 1:])
    xyz = arm.positions(q, angle_unit="deg")
    assert np.array_equal(xyz, arm.positions(in_rad, angle_unit="rad"))
    # Moving the carriage moves the probe by as much, along one axis.
    moved = q.copy()
    moved[:, 0] += 100.0
    shift = arm.positions(moved, angle_unit="deg") - xyz
    assert np.allclose(np.linalg.norm(shift, axis=1), 100.0, atol=1e-9)
    # The command line reads the same file the same way.
    poses = tmp_path / "poses.csv"
    rows = [f"P{i}," + ",".join(repr(float(v)) for v in row) for i, row in enumerate(q)]
    poses.write_text("point," + ",".join(f"q{j}" for j in range(1, 8)) + "\n" + "\n".join(rows) + "\n")
    printed = cli("points", "--arm", TRACK, "--data", str(poses)).splitlines()[1:]
    assert printed == [f"P{i},{x:.6f},{y:.6f},{z:.6f}" for i, (x, y, z) in enumerate(xyz)]


def test_from_params_takes_joint_types():
    arm = aacmm.Arm.from_file(TRACK)
    same = aacmm.Arm.from_params(7, arm.params, joint_types="PRRRRRR")
    assert same.joint_types == "PRRRRRR"
    q = np.radians(track_readings())
    q[:, 0] = 250.0
    assert np.array_equal(same.positions(q), arm.positions(q))
    # Without the types every joint turns: another arm.
    revolute = aacmm.Arm.from_params(7, arm.params)
    assert revolute.joint_types == "RRRRRRR"
    assert not np.allclose(revolute.positions(q), arm.positions(q))
    with pytest.raises(ValueError, match="joint_types"):
        aacmm.Arm.from_params(7, arm.params, joint_types="PRRX")
    with pytest.raises(ValueError, match="joint_types"):
        aacmm.Arm.from_params(7, arm.params, joint_types="PRRRRR")


def test_data_sets_keep_a_slide_in_mm():
    q = track_readings()[:12]
    labels = ["A"] * 6 + ["B"] * 6
    data = aacmm.DataSet(labels, q, angle_unit="deg", joint_types="PRRRRRR")
    assert np.array_equal(data.q[:, 0], q[:, 0])
    assert np.allclose(data.q[:, 1:], np.radians(q[:, 1:]))


def test_positions_from_arrays_keep_a_slide_in_mm():
    arm = aacmm.Arm.from_file(TRACK)
    q = track_readings()[:20]
    xyz = arm.positions(q, angle_unit="deg")
    data = aacmm.DataSet.from_positions(q, xyz, angle_unit="deg", joint_types="PRRRRRR")
    seen = data.positions["q"]
    assert np.array_equal(seen[:, 0], q[:, 0])
    assert np.allclose(seen[:, 1:], np.radians(q[:, 1:]), rtol=0, atol=1e-15)
    # Added to touches of the track, the touches' types hold.
    labels = ["A"] * 6 + ["B"] * 6
    touches = aacmm.DataSet(labels, q[:12], angle_unit="deg", joint_types="PRRRRRR")
    both = touches.with_positions(q, xyz, angle_unit="deg")
    assert np.array_equal(both.positions["q"][:, 0], q[:, 0])
    with pytest.raises(ValueError, match="joint_types"):
        aacmm.DataSet.from_positions(q, xyz, joint_types="PRR")
