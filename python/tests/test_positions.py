"""Reference positions (a laser tracker's positions of the probe, in its own
frame): data sets from arrays and files, the position noise, calibration
against them with each frame's registration fitted, held-out positions, and
every bad input refused with a message naming the argument."""

import json
import pathlib

import numpy as np
import pytest

import aacmm
from conftest import ARM, LENGTHS, POSES

# What a calibration on positions alone cannot determine from the paper's
# nominal arm (fix="auto"): a turn about and a slide along the base axis
# (the frame absorbs them) and the redundant parameters of the last link.
# The simulated true arm differs from the nominal only elsewhere, so that the
# fitted frame must be the true one.
NOT_DETERMINED = {"theta1", "d1", "alpha6", "theta6", "Bx", "By"}


def rotation(w):
    """R = exp([w]×) (Rodrigues), w a rotation vector (rad)."""
    theta = np.linalg.norm(w)
    k = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]]) / theta
    return np.eye(3) + np.sin(theta) * k + (1 - np.cos(theta)) * k @ k


def true_arm(nominal, rng):
    """The nominal arm with random errors (lengths σ 0.3 mm, angles σ 0.05°)
    on the parameters positions can determine."""
    params = nominal.params.copy()
    for i, name in enumerate(nominal.param_names):
        if name in NOT_DETERMINED:
            continue
        angle = name.startswith(("alpha", "theta"))
        params[i] += rng.normal() * (np.radians(0.05) if angle else 0.3)
    return aacmm.Arm.from_params(nominal.joints, params, name="true")


def random_frame(rng, angle_deg=50.0, distance_mm=3000.0):
    """A station: a rotation vector (rad) of `angle_deg` about a random axis,
    and a translation `distance_mm` away."""
    axis = rng.normal(size=3)
    direction = rng.normal(size=3)
    w = np.radians(angle_deg) * axis / np.linalg.norm(axis)
    return w, distance_mm * direction / np.linalg.norm(direction)


def seen(arm, w, t, poses, rng, noise_mm, noise_mm_per_m=0.0):
    """What a tracker at (w, t) sees of `arm`'s probe in `poses` random
    poses (readings anywhere in ±180°), with Gaussian noise per coordinate of
    σ = noise_mm + noise_mm_per_m · distance from the tracker (m)."""
    q = rng.uniform(-np.pi, np.pi, size=(poses, arm.joints))
    y = arm.positions(q) @ rotation(w).T + t
    sigma = noise_mm + noise_mm_per_m * np.linalg.norm(y, axis=1, keepdims=True) / 1000
    return q, y + sigma * rng.normal(size=y.shape)


@pytest.fixture
def nominal():
    return aacmm.Arm.from_file(ARM)


def write_positions(path, q_deg, xyz):
    """A positions file (readings in degrees), numbers as Python writes them
    (shortest round trip)."""
    header = ["point", *(f"q{j}" for j in range(1, q_deg.shape[1] + 1)), "x", "y", "z"]
    lines = [",".join(header)]
    for i in range(len(xyz)):
        lines.append(",".join([f"P{i + 1}", *(repr(float(v)) for v in (*q_deg[i], *xyz[i]))]))
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_tracker_campaign_finds_the_true_arm_and_frame(nominal):
    rng = np.random.default_rng(11)
    truth = true_arm(nominal, rng)
    w, t = random_frame(rng)
    q, xyz = seen(truth, w, t, 200, rng, 0.01)
    data = aacmm.DataSet.from_positions(q, xyz)
    assert len(data) == 0 and data.joints == 6 and data.points == []
    assert data.poses_file == data.positions_file == "<arrays>" and data.lengths_file is None
    rows = data.positions
    assert rows["labels"] == [f"P{i}" for i in range(1, 201)] and set(rows["frames"]) == {"instrument"}
    assert np.array_equal(rows["q"], q) and np.array_equal(rows["xyz"], xyz)
    assert np.isnan(rows["uncertainty"]).all()
    assert "200 reference positions in 1 frame" in repr(data)
    # Held out: 100 new poses seen from the same station.
    q2, xyz2 = seen(truth, w, t, 100, rng, 0.01)
    held_out = aacmm.DataSet.from_positions(q2, xyz2)

    cal = aacmm.calibrate(nominal, data, noise=aacmm.Noise(position_mm=0.01), validate=held_out)
    assert cal.successful, cal.report["verdict"]
    assert set(cal.fixed) == NOT_DETERMINED
    assert np.allclose(cal.params, truth.params, atol=0.01)
    frame = cal.frames["instrument"]
    assert list(cal.frames) == ["instrument"]
    assert np.abs(frame["rotation_deg"] - np.degrees(w)).max() < 0.01
    assert np.abs(frame["translation_mm"] - t).max() < 0.05
    assert np.allclose(frame["rotation_matrix"], rotation(w), atol=1e-5)
    assert np.allclose(frame["rotation_matrix"] @ frame["rotation_matrix"].T, np.eye(3), atol=1e-12)
    for key in ("small_rotation_sigma_deg", "translation_sigma_mm"):
        assert frame[key].shape == (3,) and (0 < frame[key]).all() and (frame[key] < 0.01).all()
    # The frames' columns in the report (deg, mm).
    auxiliary = {e["name"]: e for e in cal.report["calibration"]["auxiliary"]}
    for k, axis in enumerate(("rx", "ry", "rz")):
        assert np.isclose(auxiliary[f"instrument.{axis}"]["calibrated"], frame["rotation_deg"][k], rtol=1e-14)
    # The figures: 3-D errors |R p + t - y|, before (the nominal arm,
    # registered) and after, on the fitted and on the held-out positions.
    summary = cal.summary
    fitted, held = summary["fitted"], summary["held_out"]
    assert fitted["after"]["positions"]["count"] == 200 and held["after"]["positions"]["count"] == 100
    for figures in (fitted, held):
        after, before = figures["after"]["positions"], figures["before"]["positions"]
        assert after["rms"] < 0.03 and after["max"] < 0.08 and before["rms"] > 10 * after["rms"]
    assert cal.report["validation"]["held_out"]["data_file"] == "<arrays>"
    assert cal.report["positions"] == 200 and cal.report["positions_file"] == "<arrays>"


def test_stations_with_stated_uncertainties(nominal):
    """Two stations (frames), each with its own fitted registration; the
    rows' own uncertainties weigh them (no noise model), in degrees."""
    rng = np.random.default_rng(5)
    truth = true_arm(nominal, rng)
    stations = {"east": random_frame(rng, 120.0, 2500.0), "west": random_frame(rng, 30.0, 3500.0)}
    q, xyz, frames = [], [], []
    for name, (w, t) in stations.items():
        qs, ys = seen(truth, w, t, 120, rng, 0.01)
        q.append(qs)
        xyz.append(ys)
        frames += [name] * len(ys)
    q, xyz = np.degrees(np.vstack(q)), np.vstack(xyz)
    labels = [f"{f}-{i}" for i, f in enumerate(frames)]
    data = aacmm.DataSet.from_positions(q, xyz, frames=frames, uncertainty=0.01, labels=labels, angle_unit="deg")
    assert data.positions["labels"] == labels and data.positions["frames"] == frames
    assert np.allclose(data.positions["q"], np.radians(q), rtol=1e-15, atol=0)
    assert (data.positions["uncertainty"] == 0.01).all()
    cal = aacmm.calibrate(nominal, data)
    assert cal.successful, cal.report["verdict"]
    assert list(cal.frames) == ["east", "west"]
    for name, (w, t) in stations.items():
        frame = cal.frames[name]
        assert np.abs(frame["rotation_deg"] - np.degrees(w)).max() < 0.01, name
        assert np.abs(frame["translation_mm"] - t).max() < 0.05, name
    assert cal.summary["fitted"]["after"]["positions"]["rms"] < 0.03
    # Uncertainties per row, NaN (or None) for not stated: the noise model
    # applies there.
    u = np.full(len(xyz), 0.01)
    u[::3] = np.nan
    mixed = aacmm.DataSet.from_positions(q, xyz, frames=frames, uncertainty=u, angle_unit="deg")
    stated = mixed.positions["uncertainty"]
    assert np.isnan(stated[::3]).all() and (stated[1::3] == 0.01).all()
    listed = aacmm.DataSet.from_positions(q[:4], xyz[:4], uncertainty=[None, 0.02, 0.03, 0.04], angle_unit="deg")
    assert np.isnan(listed.positions["uncertainty"][0])
    cal = aacmm.calibrate(nominal, mixed, noise=aacmm.Noise(position_mm=0.01))
    assert cal.successful and cal.summary["fitted"]["after"]["positions"]["rms"] < 0.03


def test_positions_files_calibrate_as_the_cli_does(cli, nominal, tmp_path):
    """A positions file read by the package (alone, and with held-out
    positions) gives the command line's calibration.json byte for byte; the
    same rows as arrays give the same arm."""
    rng = np.random.default_rng(3)
    truth = true_arm(nominal, rng)
    w, t = random_frame(rng)
    q, xyz = seen(truth, w, t, 150, rng, 0.01, 0.002)
    q2, xyz2 = seen(truth, w, t, 60, rng, 0.01, 0.002)
    fitted = write_positions(tmp_path / "positions.csv", np.degrees(q), xyz)
    held = write_positions(tmp_path / "held.csv", np.degrees(q2), xyz2)
    out = tmp_path / "cli"
    cli(
        "calibrate", "--arm", ARM, "--positions", fitted, "--position-noise", "0.01+0.002/m",
        "--validate-positions", held, "--out", out,
    )
    data = aacmm.DataSet.from_files(positions=fitted)
    assert data.poses_file == data.positions_file == str(fitted) and len(data) == 0
    assert np.allclose(data.positions["q"], q, rtol=0, atol=1e-14)
    noise = aacmm.Noise(position_mm=0.01, position_mm_per_m=0.002)
    validate = aacmm.DataSet.from_files(positions=held)
    cal = aacmm.calibrate(nominal, data, noise=noise, validate=validate)
    assert cal.to_json() == (out / "calibration.json").read_text()
    assert cal.arm.to_toml() in (out / "calibrated.toml").read_text()
    assert cal.successful and cal.report["noise"]["position_mm_per_m"] == 0.002
    # The [[frame]] tables of calibrated.toml, as the frames property.
    frame = cal.frames["instrument"]
    table = (out / "calibrated.toml").read_text().split("[[frame]]\n")[1]
    values = dict(line.split(" = ", 1) for line in table.splitlines() if " = " in line)
    assert values["name"] == '"instrument"'
    for key in ("rotation_deg", "translation_mm", "small_rotation_sigma_deg", "translation_sigma_mm"):
        written = [float(v) for v in values[key].strip("[]").split(",")]
        assert np.array_equal(written, frame[key]), key
    arrays = aacmm.calibrate(nominal, aacmm.DataSet.from_positions(q, xyz), noise=noise)
    assert np.allclose(arrays.params, cal.params, rtol=0, atol=1e-9)


def test_touches_and_positions_fitted_together(cli, nominal, tmp_path):
    """The paper campaign's touches and lengths with a tracker's positions
    of the campaign's true arm: one fit, as the command line's."""
    truth = aacmm.Arm.from_file("examples/paper-campaign/true_arm.toml")
    rng = np.random.default_rng(8)
    w, t = random_frame(rng)
    q, xyz = seen(truth, w, t, 80, rng, 0.01)
    touches = aacmm.DataSet.from_files(POSES, LENGTHS)
    data = touches.with_positions(q, xyz)
    assert len(data) == len(touches) == 100 and data.lengths == touches.lengths
    assert data.poses_file == POSES and data.positions_file == "<arrays>"
    assert touches.positions is None and touches.positions_file is None
    assert "80 reference positions" in repr(data)
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01, position_mm=0.01)
    cal = aacmm.calibrate(nominal, data, noise=noise)
    assert cal.successful, cal.report["verdict"]
    after = cal.summary["fitted"]["after"]
    assert after["positions"]["count"] == 80 and after["positions"]["rms"] < 0.05
    assert after["e_mean"] < cal.summary["fitted"]["before"]["e_mean"]
    assert cal.report["touches"] == 100 and cal.report["positions"] == 80
    # The same from files, as the command line reads them.
    path = write_positions(tmp_path / "tracker.csv", np.degrees(q), xyz)
    out = tmp_path / "cli"
    cli(
        "calibrate", "--arm", ARM, "--data", POSES, "--lengths", LENGTHS, "--positions", path,
        "--encoder-noise", "0.005", "--probe-noise", "0.01", "--position-noise", "0.01",
        "--out", out,
    )
    files = aacmm.DataSet.from_files(POSES, LENGTHS, positions=path)
    assert files.poses_file == POSES and files.positions_file == str(path)
    assert aacmm.calibrate(nominal, files, noise=noise).to_json() == (out / "calibration.json").read_text()


def test_noise_of_positions():
    n = aacmm.Noise(position_mm=0.015, position_mm_per_m=0.006)
    assert (n.position_mm, n.position_mm_per_m, n.stated) == (0.015, 0.006, False)
    assert "position_mm=0.015, position_mm_per_m=0.006" in repr(n)
    assert aacmm.Noise().position_mm is None and aacmm.Noise().position_mm_per_m is None
    with pytest.raises(ValueError, match="^position_mm = -1: must be a finite number > 0$"):
        aacmm.Noise(position_mm=-1)
    with pytest.raises(ValueError, match="^position_mm = 0: "):
        aacmm.Noise(position_mm=0)
    with pytest.raises(ValueError, match="^position_mm_per_m = NaN: must be a finite number"):
        aacmm.Noise(position_mm=0.01, position_mm_per_m=float("nan"))
    with pytest.raises(ValueError, match="^position_mm_per_m = 0.006: .*needs its constant part"):
        aacmm.Noise(position_mm_per_m=0.006)


def test_noise_of_orientations():
    n = aacmm.Noise(position_mm=0.015, orientation_deg=0.01)
    assert n.orientation_deg == 0.01
    assert repr(n).endswith(", orientation_deg=0.01)")
    assert aacmm.Noise().orientation_deg is None and "orientation" not in repr(aacmm.Noise())
    with pytest.raises(ValueError, match="^orientation_deg = -1: must be a finite number > 0$"):
        aacmm.Noise(orientation_deg=-1)


@pytest.fixture
def good():
    """Readings (rad) and positions of one frame, 5 rows."""
    rng = np.random.default_rng(1)
    return rng.uniform(-3, 3, size=(5, 6)), rng.normal(scale=500, size=(5, 3))


def test_bad_position_arrays_name_the_argument_and_row(good):
    q, xyz = good
    from_positions = aacmm.DataSet.from_positions
    cases = [
        ((q.ravel(), xyz), {}, r"^q: shape \[30\]; expected \(n, joints\)"),
        ((q[:, :0], xyz[:0]), {}, r"^q: shape \[5, 0\]"),
        ((np.zeros((0, 6)), np.zeros((0, 3))), {}, "^q: no rows"),
        ((q, xyz[:4]), {}, r"^xyz: shape \[4, 3\]; expected \(5, 3\)"),
        ((q, xyz[:, :2]), {}, r"^xyz: shape \[5, 2\]; expected \(5, 3\)"),
        ((q, [["a", "b", "c"]] * 5), {}, "^xyz: expected an array of numbers"),
        ((q, xyz), {"angle_unit": "grad"}, "^angle_unit"),
        ((q, xyz), {"frames": ["a"] * 4}, "^frames: 4 frames for 5 rows of q$"),
        ((q, xyz), {"frames": ["a", "a", "", "a", "a"]}, r"^frames\[2\]: empty frame name$"),
        ((q, xyz), {"frames": ""}, "^frames: empty frame name$"),
        ((q, xyz), {"frames": 3}, "^frames: expected a sequence of 5 frames"),
        ((q, xyz), {"labels": ["A"] * 6}, "^labels: 6 labels for 5 rows of q$"),
        ((q, xyz), {"labels": "A"}, "^labels: a str; expected a sequence of 5 labels"),
        ((q, xyz), {"labels": ["A", " ", "C", "D", "E"]}, r"^labels\[1\]: empty label name$"),
        ((q, xyz), {"uncertainty": [0.01] * 4}, r"^uncertainty: shape \[4\]; expected \(5,\)"),
        ((q, xyz), {"uncertainty": np.zeros((5, 1))}, r"^uncertainty: shape \[5, 1\]"),
        ((q, xyz), {"uncertainty": -0.01}, "^uncertainty = -0.01: must be positive"),
        ((q, xyz), {"uncertainty": [0.01, 0.01, 0, 0.01, 0.01]}, r"^uncertainty\[2\] = 0: must be positive"),
        ((q, xyz), {"uncertainty": [0.01, np.inf, 0.01, 0.01, 0.01]}, r"^uncertainty\[1\] = inf"),
    ]
    for args, kwargs, message in cases:
        with pytest.raises(ValueError, match=message):
            from_positions(*args, **kwargs)
    bad = q.copy()
    bad[3, 4] = np.nan
    with pytest.raises(ValueError, match=r"^q\[3, 4\] = NaN: readings must be finite numbers$"):
        from_positions(bad, xyz)
    bad = xyz.copy()
    bad[2, 2] = -np.inf
    with pytest.raises(ValueError, match=r"^xyz\[2, 2\] \(z\) = -inf: positions must be finite"):
        from_positions(q, bad)
    # In degrees too: the reading as given.
    bad = np.degrees(q)
    bad[0, 1] = np.inf
    with pytest.raises(ValueError, match=r"^q\[0, 1\] = inf"):
        from_positions(bad, xyz, angle_unit="deg")


def test_frames_that_cannot_be_registered_are_refused(good):
    q, xyz = good
    from_positions = aacmm.DataSet.from_positions
    # A frame with only one row (or two): its registration has six unknowns.
    with pytest.raises(ValueError, match=r"^frames: frame `b` has 1 distinct position\(s\).*first row is 4\)$"):
        from_positions(q, xyz, frames=["a", "a", "a", "a", "b"])
    with pytest.raises(ValueError, match=r"^frames: frame `a` has 2 distinct.*first row is 0\)$"):
        from_positions(q, xyz, frames=["a", "a", "b", "b", "b"])
    # Without frames, every row is in one frame: named by xyz.
    with pytest.raises(ValueError, match=r"^xyz: frame `instrument` has 2 distinct.*first row is 0\)$"):
        from_positions(q[:2], xyz[:2])
    same = np.repeat(xyz[:1], 5, axis=0)
    with pytest.raises(ValueError, match="^xyz: frame `instrument` has 1 distinct"):
        from_positions(q, same)
    line = np.outer(np.arange(5.0), [1.0, 2.0, 3.0]) + 100.0
    with pytest.raises(ValueError, match="^xyz: the positions of frame `instrument` lie on one line"):
        from_positions(q, line)
    # Each frame on its own: three rows that span a plane are enough.
    data = from_positions(q, xyz, frames="station")
    assert data.positions["frames"] == ["station"] * 5
    assert len(from_positions(q[:3], xyz[:3]).positions["labels"]) == 3


def test_positions_added_to_touches_and_files_are_checked(good, tmp_path):
    q, xyz = good
    touches = aacmm.DataSet.from_files(POSES, LENGTHS)
    with pytest.raises(ValueError, match=r"^q: shape \[5, 7\]; expected \(n, 6\) for the data set's 6 joints"):
        touches.with_positions(np.c_[q, np.zeros(5)], xyz)
    with pytest.raises(ValueError, match=r"^frames: frame `x` has 1 .*first row is 4\)$"):
        touches.with_positions(q, xyz, frames=["w"] * 4 + ["x"])
    both = touches.with_positions(q, xyz)
    with pytest.raises(ValueError, match=r"already has 5 reference positions \(from <arrays>\)"):
        both.with_positions(q, xyz)
    with pytest.raises(ValueError, match="^give poses, positions or both$"):
        aacmm.DataSet.from_files()
    with pytest.raises(ValueError, match="^lengths: "):
        aacmm.DataSet.from_files(lengths=LENGTHS, positions=POSES)
    bad = tmp_path / "bad.csv"
    bad.write_text("point,q1,q2,q3,q4,q5,q6,x,y,z,frame\nA,1,2,3,4,5,6,1,2,3,a\nB,1,2,3,4,5,6,1,2,3,b\n")
    with pytest.raises(aacmm.InputError, match=r"bad\.csv:2: field `frame`: frame `a` has 1 distinct"):
        aacmm.DataSet.from_files(positions=bad)
    with pytest.raises(aacmm.InputError, match=r"bad\.csv:1"):
        aacmm.DataSet.from_files(positions=bad, joints=7)
    with pytest.raises(OSError, match="missing.csv"):
        aacmm.DataSet.from_files(positions=tmp_path / "missing.csv")


def test_positions_alone_cannot_be_evaluated_or_cross_validated(nominal, good):
    """evaluate scores touches; the figures at positions are a calibration's."""
    q, xyz = good
    data = aacmm.DataSet.from_positions(q, nominal.positions(q) + 1000.0)
    with pytest.raises(ValueError, match="^data: no touches to evaluate"):
        aacmm.evaluate(nominal, data)
    with pytest.raises(ValueError, match="^cross_validate = 2: "):
        aacmm.calibrate(nominal, data, cross_validate=2)
    seven = aacmm.DataSet.from_positions(np.c_[q, q[:, :1]], xyz)
    with pytest.raises(ValueError, match="^validate: the arm has 6 joints, the data 7$"):
        aacmm.calibrate(nominal, data, validate=seven)
    with pytest.raises(ValueError, match="^data: the arm has 6 joints, the data 7$"):
        aacmm.calibrate(nominal, seven)



def test_held_out_positions_in_an_unfitted_frame(nominal):
    """Held-out positions in a frame the fit does not have are refused with
    the fitted frames' names; ``register_held_out`` registers them on
    themselves, and the report says so (as ``--register-held-out``)."""
    rng = np.random.default_rng(12)
    truth = true_arm(nominal, rng)
    w, t = random_frame(rng)
    q, xyz = seen(truth, w, t, 150, rng, 0.01)
    q2, xyz2 = seen(truth, w, t, 40, rng, 0.01)
    data = aacmm.DataSet.from_positions(q, xyz)
    elsewhere = aacmm.DataSet.from_positions(q2, xyz2, frames=["station"] * 40)
    noise = aacmm.Noise(position_mm=0.01)
    with pytest.raises(Exception, match="held-out frame `station` was not fitted .*`instrument`"):
        aacmm.calibrate(nominal, data, noise=noise, validate=elsewhere)
    cal = aacmm.calibrate(nominal, data, noise=noise, validate=elsewhere, register_held_out=True)
    assert cal.report["validation"]["held_out"]["registered_on_itself"] == ["station"]
    same = aacmm.DataSet.from_positions(q2, xyz2)
    cal = aacmm.calibrate(nominal, data, noise=noise, validate=same)
    assert "registered_on_itself" not in cal.report["validation"]["held_out"]


def test_tool_points_from_arrays_are_fitted_and_read_back(nominal, tmp_path):
    """Positions of two markers (`tools=` per row) and of the probe: each
    marker's offset is fitted with the arm (`Calibration.tools`, within 4σ
    of the truth) and an unknown tool name is refused by row."""
    rng = np.random.default_rng(5)
    truth = true_arm(nominal, rng)
    markers = {"m1": np.array([40.0, 0.0, 95.0]), "m2": np.array([-30.0, 25.0, 60.0])}
    nominal_at = {k: v + rng.normal(size=3) * 0.5 for k, v in markers.items()}
    arm_file = tmp_path / "arm.toml"
    arm_file.write_text(
        (pathlib.Path(__file__).resolve().parents[2] / ARM).read_text()
        + "".join(
            f'\n[[tool]]\nname = "{k}"\noffset_mm = [{", ".join(repr(float(x)) for x in v)}]\n'
            for k, v in nominal_at.items()
        )
    )
    arm = aacmm.Arm.from_file(str(arm_file))
    w, t = random_frame(rng)
    qs, ys, tools = [], [], []
    for name in ["", "m1", "m2"]:
        params = truth.params.copy()
        if name:
            params[-3:] = markers[name]
        seen_by = aacmm.Arm.from_params(truth.joints, params, name="seen")
        q, y = seen(seen_by, w, t, 150, rng, 0.01)
        qs.append(q)
        ys.append(y)
        tools += [name] * len(q)
    q, xyz = np.vstack(qs), np.vstack(ys)
    noise = aacmm.Noise(position_mm=0.01)
    data = aacmm.DataSet.from_positions(q, xyz, tools=tools)
    cal = aacmm.calibrate(arm, data, method="lm", noise=noise)
    assert cal.successful, cal.verdict
    assert sorted(cal.tools) == ["m1", "m2"]
    for name, fitted in cal.tools.items():
        err = fitted["offset_mm"] - markers[name]
        assert np.all(np.abs(err) <= 4 * fitted["sigma_mm"]), (name, err, fitted["sigma_mm"])
    # No tool named: nothing to report.
    plain = aacmm.calibrate(arm, aacmm.DataSet.from_positions(qs[0], ys[0]), method="lm", noise=noise)
    assert plain.tools == {}
    # One name for every row, and a name the arm does not have.
    one = aacmm.DataSet.from_positions(qs[1], ys[1], tools="m1")
    assert aacmm.calibrate(arm, one, method="lm", noise=noise).tools.keys() == {"m1"}
    with pytest.raises(aacmm.CalibrationError, match=r"<arrays>:1: field `tool`: `m3`"):
        aacmm.calibrate(arm, aacmm.DataSet.from_positions(qs[1], ys[1], tools="m3"), method="lm")
    with pytest.raises(ValueError, match=r"tools: 2 names for 150 rows of q"):
        aacmm.DataSet.from_positions(qs[1], ys[1], tools=["m1", "m2"])
