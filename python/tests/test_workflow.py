"""Data sets, evaluation, identification, simulation and calibration against
the command line's outputs."""

import json
import threading
import time

import numpy as np
import pytest

import aacmm
from conftest import ARM, LENGTHS, POSES, REPO, longest_stall, read_lengths, read_poses


def test_a_data_set_from_files_and_from_arrays_is_the_same(data):
    labels, q = read_poses()
    arrays = aacmm.DataSet(labels, q, read_lengths(), angle_unit="deg")
    assert len(arrays) == len(data) == 100
    assert arrays.points == data.points and arrays.labels == data.labels
    assert np.array_equal(arrays.q, data.q)
    assert arrays.lengths == data.lengths
    assert data.joints == 6 and data.poses_file == POSES and data.lengths_file == LENGTHS
    assert arrays.poses_file == "<arrays>"
    assert data.source_of(0) == f"{POSES}:2"
    no_lengths = aacmm.DataSet(labels, np.radians(q))
    assert no_lengths.lengths == [] and no_lengths.lengths_file is None


def test_evaluate_equals_the_cli_json(cli, arm, data, tmp_path):
    out = tmp_path / "evaluation.json"
    cli("evaluate", "--arm", ARM, "--data", POSES, "--lengths", LENGTHS, "--json", out)
    assert aacmm.evaluate(arm, data) == json.loads(out.read_text())["evaluation"]


def test_identify_equals_the_cli_json(cli, arm, data, tmp_path):
    out = tmp_path / "identify.json"
    cli(
        "identify", "--arm", ARM, "--data", POSES, "--lengths", LENGTHS,
        "--encoder-noise", "0.005", "--probe-noise", "0.01", "--json", out,
    )
    ours = aacmm.identify(arm, data, noise=aacmm.Noise(encoder_deg=0.005, probe_mm=0.01), threads=2)
    assert ours == json.loads(out.read_text())["identification"]


def test_calibration_equals_the_cli_files(cli, arm, data, tmp_path):
    theirs, ours = tmp_path / "cli", tmp_path / "py"
    printed = cli(
        "calibrate", "--arm", ARM, "--data", POSES, "--lengths", LENGTHS,
        "--encoder-noise", "0.005", "--probe-noise", "0.01", "--cross-validate", "3",
        "--out", theirs,
    )
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
    cal = aacmm.calibrate(arm, data, noise=noise, cross_validate=3, threads=1)
    assert cal.to_json() == (theirs / "calibration.json").read_text()
    # The command line's arm file is the arm and the verdict it was given.
    written_arm = (theirs / "calibrated.toml").read_text()
    assert written_arm == cal.arm.to_toml() + "\n[verdict]\nusable = true\nreasons = []\nnotes = []\n"
    assert printed.startswith(cal.text()) and "Parameters (mm, deg" in cal.text()
    # write(dir) writes the command line's files, byte for byte, apart from
    # the wall times in timing.json.
    written = cal.write(ours)
    # As the command line without --force: an earlier result is kept.
    with pytest.raises(OSError, match=r"earlier result \(calibrated.toml\).*force=True"):
        cal.write(ours)
    assert cal.write(ours, force=True) == written
    with pytest.raises(ValueError, match="empty"):
        cal.write("")
    names = sorted(p.name for p in theirs.iterdir())
    assert sorted(p.name for p in written) == names and "report.html" in names
    assert all(p.parent == ours for p in written)
    for name in names:
        if name == "timing.json":
            a, b = (json.loads((d / name).read_text()) for d in (ours, theirs))
            assert [p["name"] for p in a["phases"]] == [p["name"] for p in b["phases"]]
            assert a["total_ms"] > 0
        else:
            assert (ours / name).read_bytes() == (theirs / name).read_bytes(), name
    # The arrays are the report's numbers in mm and rad.
    report = cal.report
    names = aacmm.param_names(6)
    for i, e in enumerate(report["calibration"]["parameters"]):
        assert e["name"] == names[i]
        value = cal.params[i] if e["unit"] == "mm" else np.degrees(cal.params[i])
        assert np.isclose(value, e["calibrated"], rtol=1e-12, atol=1e-12)
        if e["fixed"] is None:
            sigma = cal.sigma[i] if e["unit"] == "mm" else np.degrees(cal.sigma[i])
            assert np.isclose(sigma, e["sigma"], rtol=1e-12, atol=0)
        else:
            assert np.isnan(cal.sigma[i]) and cal.fixed[e["name"]] == e["fixed"]
    assert len(cal.free) == 21 == cal.correlation.shape[0] == cal.summary["free_parameters"]
    assert np.allclose(np.diag(cal.correlation), 1.0)
    s = cal.summary
    assert s["successful"] and s["converged"] and cal.successful and s["method"] == "global"
    assert "final LM" in s["stop_text"] and "global" in s["stop"]
    assert s["fitted"]["after"]["e_mean"] < s["fitted"]["before"]["e_mean"] / 10
    assert len(s["cross_validation"]) == 3 and s["held_out"] is None
    # Threads change nothing; arrays give the same parameters as files.
    labels, q = read_poses()
    arrays = aacmm.DataSet(labels, q, read_lengths(), angle_unit="deg")
    again = aacmm.calibrate(arm, arrays, noise=noise, fix=cal.report["fix"], threads=2)
    assert np.array_equal(again.params, cal.params)
    assert np.array_equal(again.sigma, cal.sigma, equal_nan=True)


def test_successful_is_the_verdict_not_the_solvers_convergence(arm, data):
    """Noise overstated 3000 times: the solver converges (to the right arm),
    but χ² is far below its range, so the σ cannot be trusted and the
    verdict refuses the calibration — `successful`, `summary["successful"]`
    and the report's verdict all say so; the solver's own criterion is
    `converged`. Accepting a poor fit makes all three usable."""
    loud = aacmm.Noise(encoder_deg=30, probe_mm=100)
    for accept in (False, True):
        cal = aacmm.calibrate(arm, data, noise=loud, accept_poor_fit=accept)
        s, verdict = cal.summary, cal.report["verdict"]
        assert cal.successful == s["successful"] == verdict["usable"] == accept, verdict
        assert s["converged"] and cal.report["calibration"]["solver"]["successful"]
        assert s["fitted"]["after"]["e_mean"] < 0.06
        assert repr(cal).startswith(f'Calibration(method="global", successful={str(accept).lower()},')
        if accept:
            assert verdict["notes"][0].startswith("accepted on request: ")
        else:
            assert "overstated" in verdict["reasons"][0], verdict


def test_the_verdict_is_typed_and_said_in_pythons_words(arm, data):
    """A refused calibration's `verdict`: each reason's `kind`, its figures
    as a dict, and its sentence naming Python's arguments, never a flag;
    the report keeps the command line's sentences."""
    loud = aacmm.Noise(encoder_deg=30, probe_mm=100)
    cal = aacmm.calibrate(arm, data, noise=loud)
    v = cal.verdict
    assert isinstance(v, aacmm.Verdict) and not v.usable
    assert len(v.reasons) == len(cal.report["verdict"]["reasons"])
    first = v.reasons[0]
    assert isinstance(first, aacmm.VerdictEntry)
    assert first.kind == "chi_square", first
    chi = first.data["chi"]
    assert chi["dof"] > 0 and chi["verdict"] == "residuals_too_small"
    assert first.data["stated"]["probe_mm"] == 100
    assert "the Birge ratio σ̂₀ = √(χ²/dof) = " in first.text
    assert "Noise(encoder_deg=30.0000, probe_mm=100.0000)" in first.text
    assert "leave it unstated (noise=None)" in first.text
    assert first.text.endswith("accept_poor_fit=True.")
    for entry in v.reasons + v.notes:
        assert "--" not in entry.text, entry.text
    cli = cal.report["verdict"]["reasons"][0]
    assert "--accept-poor-fit" in cli and "--" not in first.text
    accepted = aacmm.calibrate(arm, data, noise=loud, accept_poor_fit=True)
    assert accepted.verdict.usable and accepted.verdict.reasons == []
    note = accepted.verdict.notes[0]
    assert note.kind == "accepted" and note.data["reason"]["kind"] == "chi_square"
    assert note.text.startswith("accepted on request: χ² = ")
    with pytest.raises(ValueError, match="global_starts = 0"):
        aacmm.calibrate(arm, data, global_starts=0)


def test_readings_outside_the_joint_limits_are_warned_and_kept_as_the_cli_does(
    cli, data, tmp_path
):
    """The library's request owns the joint-limit warning: Python issues it
    and keeps it in the report, and the report is the command line's."""
    text = (REPO / ARM).read_text().replace("d = 250.0", "d = 250.0\nlimits = [-30, 30]", 1)
    limited = tmp_path / "limited.toml"
    limited.write_text(text)
    arm = aacmm.Arm.from_file(limited)
    warning = (
        f"{POSES}:3: field `q3`: 85 readings outside the arm's joint limits "
        "(first: 146.60792432509484° > 30°); check the arm file, the angle unit and the "
        "encoder zeros"
    )
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
    with pytest.warns(UserWarning) as caught:
        cal = aacmm.calibrate(arm, data, noise=noise, threads=1)
    assert [str(w.message) for w in caught] == [warning]
    assert cal.report["warnings"] == [warning]
    theirs = tmp_path / "cli"
    cli(
        "calibrate", "--arm", limited, "--data", POSES, "--lengths", LENGTHS,
        "--encoder-noise", "0.005", "--probe-noise", "0.01", "--out", theirs,
    )
    assert cal.to_json() == (theirs / "calibration.json").read_text()


def test_held_out_validation_and_fix_lists(arm, data):
    campaign = aacmm.simulate(arm, sockets=4, poses=6, seed=11)
    fix = ["theta1", "d1", "theta6", "alpha6", "Bx", "By"]
    cal = aacmm.calibrate(arm, data, method="lm", fix=fix, validate=campaign.data)
    assert set(cal.fixed) == set(fix)
    assert all(r == "fixed by the user" for r in cal.fixed.values())
    held = cal.report["validation"]["held_out"]
    assert held["data_file"] == "poses.csv" and held["figures"] == cal.summary["held_out"]
    assert cal.report["fix"] == ",".join(fix)


def test_a_prior_is_the_command_lines(cli, arm, data, tmp_path):
    spec = "length=1mm,angle=0.5deg"
    theirs = tmp_path / "cli"
    cli(
        "calibrate", "--arm", ARM, "--data", POSES, "--lengths", LENGTHS,
        "--encoder-noise", "0.005", "--probe-noise", "0.01", "--prior", spec,
        "--out", theirs,
    )
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
    cal = aacmm.calibrate(arm, data, noise=noise, prior=spec, threads=1)
    assert cal.to_json() == (theirs / "calibration.json").read_text()
    prior = cal.report["calibration"]["prior"]
    assert prior["rows"] == 21 == cal.report["calibration"]["dof"]["prior_rows"]
    assert all(p["data_share"] > 0.99 for p in prior["parameters"])
    assert "prior" not in aacmm.calibrate(arm, data, noise=noise, prior="none").report["calibration"]
    with pytest.raises(ValueError, match="prior = theta5=1mm: `theta5=1mm`: theta5 is an angle"):
        aacmm.calibrate(arm, data, prior="theta5=1mm")


def test_simulate_writes_the_cli_campaign(cli, arm, tmp_path):
    campaign = aacmm.simulate(
        arm, sockets=5, poses=6, seed=4, encoder_noise_deg=0.002, probe_noise_mm=0.003
    )
    ours, theirs = tmp_path / "py", tmp_path / "cli"
    written = campaign.write(ours)
    with pytest.raises(OSError, match=r"earlier result \(poses.csv\).*force=True"):
        campaign.write(ours)
    assert campaign.write(ours, force=True) == written
    with pytest.raises(ValueError, match="empty"):
        campaign.write("")
    cli(
        "simulate", "--arm", ARM, "--errors", "paper", "--sockets", 5, "--poses", 6,
        "--seed", 4, "--encoder-noise", 0.002, "--probe-noise", 0.003, "--out", theirs,
    )
    names = sorted(p.name for p in theirs.iterdir())
    assert sorted(str(p).rsplit("/", 1)[-1] for p in written) == names
    for name in names:
        assert (ours / name).read_bytes() == (theirs / name).read_bytes(), name
    assert campaign.q.shape == (30, 6) and campaign.sockets.shape == (5, 3)
    assert campaign.labels[:6] == ["S1"] * 6 and campaign.socket_labels[0] == "S1"
    assert len(campaign.lengths) == 3
    # The true arm puts every touch of a socket near its centre.
    xyz = campaign.true_arm.positions(campaign.q)
    centre = campaign.sockets[0]
    assert np.abs(xyz[:6] - centre).max() < 0.05
    assert len(campaign.data) == 30 and campaign.nominal.name == arm.name


def test_the_gil_is_released_during_calibration(arm, data):
    took, stall = longest_stall(lambda: aacmm.calibrate(arm, data, cross_validate=5, threads=1))
    assert took > 0.01, took
    assert stall < took / 2, (stall, took)


def test_the_example_script_runs(tmp_path):
    import subprocess
    import sys

    from conftest import REPO

    script = REPO / "python" / "examples" / "calibrate_campaign.py"
    done = subprocess.run(
        [sys.executable, str(script), str(tmp_path)], cwd=REPO, capture_output=True, text=True
    )
    assert done.returncode == 0, done.stderr
    assert "e mean: 3.6515 mm -> 0.0520 mm" in done.stdout
    assert (tmp_path / "calibration.json").read_text().startswith('{\n  "arm": "paper-table-1"')


def test_the_readme_python_example_prints_what_the_readme_says():
    import re
    import subprocess
    import sys

    from conftest import REPO

    readme = (REPO / "README.md").read_text()
    m = re.search(
        r'```sh\npython3 -m venv v && v/bin/pip install -v \./python[^\n]*\nv/bin/python -c "\n(.*?)"\n```\n\n```text\n(.*?)```',
        readme,
        re.S,
    )
    assert m, "the README's Python example is not where the test looks"
    code, printed = m.groups()
    done = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout == printed


def test_robust_keyword_downweights_a_displaced_touch(arm):
    labels, q = read_poses()
    q = [list(row) for row in q]
    q[16][1] += 0.2  # about 2 mm at the probe (degrees)
    data = aacmm.DataSet(labels, q, read_lengths(), angle_unit="deg")
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
    plain = aacmm.calibrate(arm, data, noise=noise)
    assert "robust" not in plain.report["calibration"]
    cal = aacmm.calibrate(arm, data, noise=noise, robust="cauchy")
    fit = cal.report["calibration"]["robust"]
    assert fit["loss"] == "cauchy" and fit["scale_k"] == 2.65
    low = [w["at"] for w in fit["weights"] if w["weight"] < 0.25]
    assert low == ["<arrays>:17"]
    assert cal.report["verdict"]["usable"] and not plain.report["verdict"]["usable"]


def test_a_refused_calibration_says_so_and_its_arm_file_is_refused_unless_asked(arm, tmp_path):
    """One mislabelled touch (file line 18, a touch of S2, labelled S1):
    `successful`, the report's verdict and the summary text say NOT usable
    and why; the calibrated.toml it writes is marked, and Arm.from_file
    refuses it (InputError naming the verdict) unless accept_rejected=True,
    which reads it with a warning."""
    labels, q = read_poses()
    labels = list(labels)
    assert labels[16] == "S2"
    labels[16] = "S1"
    data = aacmm.DataSet(labels, q, read_lengths(), angle_unit="deg")
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
    cal = aacmm.calibrate(arm, data, noise=noise, threads=1)
    verdict = cal.report["verdict"]
    assert not cal.successful and not verdict["usable"] and verdict["reasons"]
    assert "Verdict: NOT usable — " in cal.text()
    cal.write(tmp_path)
    written = tmp_path / "calibrated.toml"
    assert written.read_text().startswith("# NOT USABLE")
    with pytest.raises(aacmm.InputError, match=r"field `verdict`: this arm file .* NOT usable"):
        aacmm.Arm.from_file(written)
    with pytest.warns(UserWarning, match="NOT usable"):
        again = aacmm.Arm.from_file(written, accept_rejected=True)
    assert "NOT usable" in again.warnings[0]


def _calibrate_in_child(arm, data, noise, queue):
    cal = aacmm.calibrate(arm, data, method="lm", noise=noise, threads=2)
    queue.put(cal.params.tolist())


def test_a_child_forked_after_the_worker_threads_started_calibrates(arm):
    """The library's worker threads start once per process. A child forked
    after they did (multiprocessing's default on Linux) inherits the pool
    but not its threads: its calibration runs on its own thread, with the
    parent's result, instead of waiting for workers that do not exist."""
    import multiprocessing

    # 520 points: 9 chunks of the normal equations, so 2 threads share them.
    campaign = aacmm.simulate(arm, sockets=520, poses=4, seed=5, encoder_noise_deg=0.005, probe_noise_mm=0.01)
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
    parent = aacmm.calibrate(arm, campaign.data, method="lm", noise=noise, threads=2)
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_calibrate_in_child, args=(arm, campaign.data, noise, queue))
    child.start()
    try:
        params = queue.get(timeout=120)
    finally:
        child.join(timeout=10)
        if child.is_alive():
            child.kill()
    assert child.exitcode == 0
    assert params == parent.params.tolist()


def test_ctrl_c_stops_a_calibration_with_keyboard_interrupt(arm):
    """Ctrl-C during a long calibration raises KeyboardInterrupt promptly:
    the calling thread runs Python's signal handlers while the work runs
    without the GIL, and sets the token every solver checks (annealing at
    each temperature). No result comes back."""
    import os
    import signal

    # Annealing 4 000 touches, then ten folds of it: 3–4 s in a release
    # build (one anneal 0.33 s here), minutes in a debug one — far beyond
    # the interrupt either way (the folds check the token too).
    campaign = aacmm.simulate(arm, sockets=400, poses=10, seed=3, encoder_noise_deg=0.005, probe_noise_mm=0.01)
    sent = []

    def interrupt():
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)

    timer = threading.Timer(0.3, interrupt)
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        aacmm.calibrate(arm, campaign.data, method="sa", cross_validate=10, threads=1)
    latency = time.monotonic() - sent[0]
    timer.join()
    assert latency < 1.0, latency
