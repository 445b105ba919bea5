"""Issue 29's hostile calls of 2026-11-25, re-run as they were written
there: each gives an ordinary exception (or the right result), the process
survives, messages stay short. The cases test_errors.py and
test_workflow.py already cover are not repeated here."""

import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

import aacmm
from conftest import ARM, POSES, REPO, read_poses

ISSUE_SIZES = r"""
import resource, sys
import numpy as np
import aacmm
resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))
arm = aacmm.Arm.from_file(sys.argv[1])
q = np.broadcast_to(np.zeros(6), (10**8, 6))
calls = {
    "jacobians": lambda: arm.jacobians(q),
    "positions": lambda: arm.positions(q),
    "joint_jacobian": lambda: arm.joint_jacobian(q),
    "from_params": lambda: aacmm.Arm.from_params(6, np.broadcast_to(np.zeros(1), (10**10,))),
    "param_names": lambda: aacmm.param_names(10**9),
}
for name, call in calls.items():
    try:
        call()
        print(name, "accepted")
    except Exception as e:
        print(name, type(e).__name__, str(e)[:200])
"""


def test_the_issues_own_sizes():
    """Item 1 verbatim: `arm.jacobians(np.broadcast_to(np.zeros(6), (10**8,
    6)))` was a SIGABRT (64.8 GB asked for); so were positions,
    joint_jacobian, Arm.from_params with a huge array (copied before its
    length was checked) and param_names(10**9). Under a 2 GiB address
    space: MemoryError for the outputs, the length or joint count refused
    before any copy."""
    done = subprocess.run(
        [sys.executable, "-c", ISSUE_SIZES, ARM], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    got = {line.split()[0]: line.split(None, 2)[1:] for line in done.stdout.splitlines()}
    assert got["jacobians"][0] == "MemoryError", done.stdout
    assert got["positions"][0] == "MemoryError", done.stdout
    assert got["joint_jacobian"][0] == "MemoryError", done.stdout
    assert got["from_params"] == ["ValueError", "params: 10000000000 values, expected 27 (4 · joints + 3)"]
    assert got["param_names"][0] == "UnsupportedError", done.stdout
    assert "joints = 1000000000" in got["param_names"][1]


def test_fifty_megabyte_labels_give_short_messages(tmp_path, arm, data):
    """Item 3 at the issue's size: a 50 MB label, option or line."""
    huge = "L" * 50_000_000
    labels, q = read_poses()
    with pytest.raises(aacmm.InputError) as caught:
        aacmm.DataSet(labels[:3] + [huge], q[:4], angle_unit="deg")
    assert len(str(caught.value)) < 400 and "(50000000 characters)" in str(caught.value)
    for kwargs in ({"fix": huge}, {"prior": huge}):
        with pytest.raises(ValueError) as caught:
            aacmm.calibrate(arm, data, **kwargs)
        assert len(str(caught.value)) < 600 and "(50000000 characters)" in str(caught.value)
    poses = tmp_path / "p.csv"
    poses.write_text(f"point,q1,q2,q3,q4,q5,q6\n{huge},1,2,3,4,5,6\n")
    with pytest.raises(aacmm.InputError, match=r"p\.csv:2: line longer than 1 MiB") as caught:
        aacmm.DataSet.from_files(poses)
    assert len(str(caught.value)) < 400


def test_huge_values_are_shown_short(arm, data):
    """Item 7: a value of ±1e308 was shown as a 309-digit integer (cut at
    80 characters in the library's own settings, whole in simulate's, the
    prior's and the arrays'): now `1e308` wherever it is echoed."""
    labels, q = read_poses()
    q = np.radians(q)
    sim = {"sockets": 3, "poses": 5, "seed": 1}
    cases = [
        (lambda: aacmm.Noise(probe_mm=-1e308), ValueError, "probe_mm = -1e308: must be a finite number ≥ 0"),
        (lambda: aacmm.Noise(length_weight=-1e308), ValueError, "length_weight = -1e308: "),
        (lambda: aacmm.Noise(length_default_mm=-1e308), ValueError, "length_default_mm = -1e308: "),
        (lambda: aacmm.Noise(position_mm=-1e308), ValueError, "position_mm = -1e308: "),
        (
            lambda: aacmm.calibrate(arm, data, robust="huber", robust_scale=-1e308),
            ValueError,
            "robust_scale = -1e308: must be a finite number > 0",
        ),
        (lambda: aacmm.calibrate(arm, data, prior="length=-1e308mm"), ValueError, "(got -1e308 mm)"),
        (lambda: aacmm.calibrate(arm, data, prior="length=1e308mm"), ValueError, "length = 1e308 mm: above 1e12"),
        (
            lambda: aacmm.simulate(arm, **sim, probe_noise_mm=-1e308),
            ValueError,
            "probe_noise_mm: must be finite and not negative, got -1e308",
        ),
        (
            lambda: aacmm.simulate(arm, **sim, encoder_noise_deg=-1e308),
            ValueError,
            "encoder_noise_deg: must be finite and not negative, got -1e308",
        ),
        (
            lambda: aacmm.simulate(arm, **sim, errors="random", error_scale=-1e308),
            ValueError,
            "error_scale: must be finite and not negative, got -1e308",
        ),
        (
            lambda: aacmm.simulate(arm, **sim, errors="random", error_scale=1e308),
            ValueError,
            "error_scale: at most 1000 (a length σ of 400 mm; beyond, no arm), got 1e308",
        ),
        (
            lambda: aacmm.DataSet.from_positions(np.zeros((3, 6)), np.eye(3), uncertainty=-1e308),
            ValueError,
            "uncertainty = -1e308: must be positive",
        ),
        (
            lambda: aacmm.DataSet(labels, q, [("S1", "S2", -1e308)]),
            aacmm.InputError,
            "field `distance`: -1e308: must be a positive number",
        ),
        (
            lambda: aacmm.DataSet(labels, q, [("S1", "S2", 5.0, -1e308)]),
            aacmm.InputError,
            "field `uncertainty`: -1e308: must be a finite number ≥ 0",
        ),
    ]
    for i, (call, exception, expected) in enumerate(cases):
        with pytest.raises(exception) as caught:
            call()
        message = str(caught.value)
        assert expected in message and "0000000000" not in message, (i, message[:500])
    assert repr(aacmm.Noise(probe_mm=1e308, length_weight=1e300)) == (
        "Noise(encoder_deg=None, probe_mm=1e308, length_default_mm=0.001, length_weight=1e300, "
        "position_mm=None, position_mm_per_m=None)"
    )


DASH = r"""
import sys
import aacmm
arm_path, poses_path = sys.argv[1:3]
calls = {
    "Arm.from_file": lambda: aacmm.Arm.from_file("-"),
    "poses": lambda: aacmm.DataSet.from_files("-"),
    "lengths": lambda: aacmm.DataSet.from_files(poses_path, "-"),
    "positions": lambda: aacmm.DataSet.from_files(positions="-"),
    "sockets_file": lambda: aacmm.simulate(
        aacmm.Arm.from_file(arm_path), sockets_file="-", poses=5, seed=1
    ),
}
for name, call in calls.items():
    try:
        call()
        print(name, "accepted")
    except OSError as e:
        print(name, "OSError", e)
"""


def test_dash_is_a_file_not_standard_input(tmp_path, monkeypatch):
    """Item 6: a path `-` read standard input in Python (documented for C
    and the command line only) and blocked forever on an open pipe; a file
    named `-` needed `./-`. Now `-` is a file, as for Python's open()."""
    read, write = os.pipe()  # standard input: open, and never written
    try:
        done = subprocess.run(
            [sys.executable, "-c", DASH, str(REPO / ARM), str(REPO / POSES)],
            stdin=read,
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=120,
        )
    finally:
        os.close(read)
        os.close(write)
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    lines = done.stdout.splitlines()
    assert [line.split()[:2] for line in lines] == [
        [name, "OSError"] for name in ("Arm.from_file", "poses", "lengths", "positions", "sockets_file")
    ], done.stdout
    assert all("./-" in line for line in lines), done.stdout
    # A file named `-` is read by its name.
    monkeypatch.chdir(tmp_path)
    shutil.copy(REPO / ARM, tmp_path / "-")
    assert aacmm.Arm.from_file("-").joints == 6
    shutil.copy(REPO / POSES, tmp_path / "-")
    assert len(aacmm.DataSet.from_files("-")) == len(aacmm.DataSet.from_files(REPO / POSES))


FULL = r"""
import os, resource, shutil, signal, sys
import aacmm
mode, out, copy, ref, snapshot = sys.argv[1:6]
arm = aacmm.Arm.from_file(sys.argv[6])
if sys.argv[7] == "campaign":
    first = aacmm.simulate(arm, sockets=6, poses=10, seed=1)
    second = aacmm.simulate(arm, sockets=6, poses=10, seed=2)
else:
    data = aacmm.DataSet.from_files(sys.argv[8], sys.argv[9])
    first = aacmm.calibrate(arm, data, method="lm", threads=1)
    second = aacmm.calibrate(arm, data, method="lm", threads=1, noise=aacmm.Noise(probe_mm=0.01))
hard = resource.getrlimit(resource.RLIMIT_FSIZE)[1]
first.write(out)
first.write(copy)
second.write(ref)
if mode == "fsize":
    # A file may not grow beyond 2000 bytes: a write past it fails (EFBIG)
    # as on a full file system.
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (2000, hard))
else:
    # Fill the (small) file system `out` is on: ENOSPC.
    with open(os.path.join(os.path.dirname(out), "filler"), "wb", buffering=0) as f:
        try:
            while True:
                f.write(b"x" * 4096)
        except OSError:
            pass
try:
    second.write(out, force=True)
    print("accepted")
except OSError as e:
    print("OSError", e)
resource.setrlimit(resource.RLIMIT_FSIZE, (hard, hard))
shutil.copytree(out, snapshot)
"""


def full_write(tmp_path, kind, mode):
    """Runs FULL for `kind` (campaign or calibration) and `mode` (fsize, or
    fill inside a small tmpfs); returns its output and the directories: the
    output after the failed write, the first result, the second."""
    small = tmp_path / "small"
    small.mkdir()
    out, copy, ref, snapshot = small / "out", tmp_path / "copy", tmp_path / "ref", tmp_path / "after"
    args = [sys.executable, "-c", FULL, mode, out, copy, ref, snapshot, REPO / ARM, kind]
    args += [REPO / POSES, REPO / "examples/paper-campaign/lengths.csv"]
    if mode == "fill":
        mount = 'mount -t tmpfs -o size=2m tmpfs "$0" && exec "$@"'
        args = ["unshare", "-rm", "sh", "-c", mount, small, *args]
    done = subprocess.run(list(map(str, args)), capture_output=True, text=True, timeout=600)
    return done, snapshot, copy, ref


def check_whole(done, after, first, second, name, error):
    """The write failed with an OSError naming the system's error, and left
    every file whole: the first result's bytes or the second's, nothing
    else (no temporary file), and `name` (the file the issue found
    truncated or empty) as it was."""
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    assert done.stdout.startswith("OSError") and error in done.stdout, done.stdout
    names = sorted(p.name for p in after.iterdir())
    assert names == sorted(p.name for p in first.iterdir()), names
    for n in names:
        now = (after / n).read_bytes()
        assert now in ((first / n).read_bytes(), (second / n).read_bytes()), n
    assert (after / name).read_bytes() == (first / name).read_bytes()
    assert (first / name).read_bytes() != (second / name).read_bytes()


@pytest.mark.parametrize("kind,name", [("campaign", "poses.csv"), ("calibration", "calibration.json")])
def test_a_write_that_runs_out_of_room_leaves_whole_files(tmp_path, kind, name):
    """Item 6: on a full file system Calibration.write left a truncated
    calibration.json and Campaign.write an empty poses.csv. A file-size
    limit (RLIMIT_FSIZE: EFBIG past 2000 bytes) stands in for it."""
    done, after, first, second = full_write(tmp_path, kind, "fsize")
    check_whole(done, after, first, second, name, "File too large")


@pytest.mark.parametrize("kind,name", [("campaign", "poses.csv"), ("calibration", "calibration.json")])
def test_a_full_file_system_leaves_whole_files(tmp_path, kind, name):
    """Item 6 on a real full file system: a 2 MiB tmpfs (mounted in a user
    namespace, `unshare -rm`) filled before the second write: ENOSPC."""
    if shutil.which("unshare") is None:
        pytest.skip("no unshare (util-linux)")
    probe = subprocess.run(
        ["unshare", "-rm", "sh", "-c", f'mount -t tmpfs -o size=64k tmpfs "{tmp_path}"'],
        capture_output=True,
    )
    if probe.returncode != 0:
        pytest.skip(f"no tmpfs in a user namespace: {probe.stderr.decode()[:200]}")
    done, after, first, second = full_write(tmp_path, kind, "fill")
    check_whole(done, after, first, second, name, "No space left on device")
