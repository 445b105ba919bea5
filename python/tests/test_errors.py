"""Every error path raises a Python exception with the library's message;
nothing crashes the interpreter."""

import contextlib
import os

import numpy as np
import pytest

import aacmm
from conftest import ARM, LENGTHS, POSES, read_lengths, read_poses


def write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_exception_hierarchy():
    for e in (aacmm.InputError, aacmm.CalibrationError, aacmm.UnsupportedError):
        assert issubclass(e, aacmm.AacmmError) and issubclass(e, Exception)


def test_arm_files(tmp_path):
    with pytest.raises(OSError, match="missing.toml"):
        aacmm.Arm.from_file(tmp_path / "missing.toml")
    text = (aacmm.Arm.from_file(ARM).to_toml()).replace('length_unit = "mm"', 'length_unit = "furlong"')
    bad = write(tmp_path, "bad.toml", text)
    with pytest.raises(aacmm.InputError, match=r"bad\.toml:\d+: .*furlong"):
        aacmm.Arm.from_file(bad)


def test_arm_parameters():
    with pytest.raises(aacmm.UnsupportedError, match="joints = 13"):
        aacmm.Arm.from_params(13, np.zeros(55))
    with pytest.raises(ValueError, match="26 values, expected 27"):
        aacmm.Arm.from_params(6, np.zeros(26))
    bad = np.zeros(27)
    bad[3] = np.nan
    with pytest.raises(ValueError, match=r"params\[3\] \(a4\) = NaN"):
        aacmm.Arm.from_params(6, bad)
    with pytest.raises(ValueError):
        aacmm.Arm.from_params(6, ["x"] * 27)


def test_readings_of_the_wrong_shape_or_unit(arm):
    with pytest.raises(ValueError, match=r"shape \[4, 7\]"):
        arm.positions(np.zeros((4, 7)))
    with pytest.raises(ValueError, match=r"shape \[2, 3, 6\]"):
        arm.jacobians(np.zeros((2, 3, 6)))
    with pytest.raises(ValueError, match="expected an array of numbers"):
        arm.joint_jacobian([["a"] * 6])
    with pytest.raises(ValueError, match="angle_unit"):
        arm.positions(np.zeros((1, 6)), angle_unit="grad")
    with pytest.raises(ValueError, match="length_unit"):
        arm.to_toml(length_unit="parsec")


def test_poses_and_lengths_files(tmp_path):
    with pytest.raises(OSError, match="nope.csv"):
        aacmm.DataSet.from_files(tmp_path / "nope.csv")
    poses = write(tmp_path, "p.csv", "point,q1,q2,q3,q4,q5,q6\nA,1,2,3,4,5,6\nA,1,2,x,4,5,6\n")
    with pytest.raises(aacmm.InputError, match=r"p\.csv:3: field `q3`"):
        aacmm.DataSet.from_files(poses)
    # Articulated (q6 turns 34°), so the count is what is wrong: a static
    # campaign is refused as such first.
    few = write(tmp_path, "few.csv", "point,q1,q2,q3,q4,q5,q6\nA,1,2,3,4,5,6\nA,1,2,3,4,5,40\n")
    with pytest.raises(aacmm.InputError, match=r"few\.csv:2: field `point`: point `A` has 2 touches"):
        aacmm.DataSet.from_files(few)
    with pytest.raises(aacmm.InputError, match="7"):
        aacmm.DataSet.from_files(POSES, joints=7)
    lengths = write(tmp_path, "l.csv", "point_a,point_b,distance\nS1,S99,100\n")
    with pytest.raises(aacmm.InputError, match=r"l\.csv:2: field `point_b`: unknown point `S99`"):
        aacmm.DataSet.from_files(POSES, lengths)


def test_arrays():
    """Arrays are checked by the library as files are: messages name
    `<arrays>`, the 1-based touch (row of q) or length, and the field."""
    labels, q = read_poses()
    q = np.radians(q)
    with pytest.raises(aacmm.InputError, match=r"<arrays>:7: field `point`: point `X` has 2 touches"):
        aacmm.DataSet(labels[:6] + ["X", "X"], q[:8])
    bad = q.copy()
    bad[4, 2] = np.inf
    with pytest.raises(aacmm.InputError, match=r"<arrays>:5: field `q3`: inf: readings must be finite"):
        aacmm.DataSet(labels, bad)
    with pytest.raises(aacmm.InputError, match="<arrays>: 100 labels for 99 rows of readings"):
        aacmm.DataSet(labels, q[:99])
    with pytest.raises(aacmm.InputError, match="<arrays>: no touches"):
        aacmm.DataSet([], np.zeros((0, 6)))
    with pytest.raises(ValueError, match=r"shape"):
        aacmm.DataSet(labels, q.ravel())
    cases = [
        (("S1", "S77", 10.0), r"<arrays>:1: field `point_b`: unknown point `S77`"),
        (("S1", "S1", 10.0), r"<arrays>:1: field `point_b`: `S1` again: a length needs two points"),
        (("S1", "S2", -1.0), r"<arrays>:1: field `distance`: -1: must be a positive number"),
        (("S1", "S2", 5.0, -0.1), r"<arrays>:1: field `uncertainty`: -0.1: must be a finite number"),
    ]
    for length, message in cases:
        with pytest.raises(aacmm.InputError, match=message):
            aacmm.DataSet(labels, q, [length])
    with pytest.raises(aacmm.InputError, match=r"<arrays>:2: field `point_b`: the pair S2–S1 is given twice"):
        aacmm.DataSet(labels, q, [("S1", "S2", 5.0), ("S2", "S1", 5.0)])
    with pytest.raises(ValueError, match=r"lengths\[0\]: expected"):
        aacmm.DataSet(labels, q, [("S1", "S2")])
    with pytest.raises(ValueError, match=r"lengths\[0\]: expected"):
        aacmm.DataSet(labels, q, [("S1", "S2", "far")])


@contextlib.contextmanager
def refused(exception, match):
    """pytest.raises, and the message names no command-line flag: the
    library names settings, the bindings their Python arguments."""
    with pytest.raises(exception, match=match) as caught:
        yield caught
    assert "--" not in str(caught.value), caught.value


def test_noise():
    with refused(ValueError, match="probe_mm = -1"):
        aacmm.Noise(probe_mm=-1)
    with refused(ValueError, match="encoder_deg: must be a finite number ≥ 0"):
        aacmm.Noise(encoder_deg=float("nan"))
    with refused(ValueError, match="length_default_mm = inf"):
        aacmm.Noise(length_default_mm=float("inf"))
    with refused(ValueError, match="length_weight = -2: must be a finite number > 0"):
        aacmm.Noise(length_weight=-2)
    with refused(ValueError, match="probe_mm = 0: encoder and probe noise both 0"):
        aacmm.Noise(encoder_deg=0, probe_mm=0)
    assert aacmm.Noise(length_weight=0).length_weight is None
    n = aacmm.Noise(encoder_deg=0.01)
    assert n.stated and n.encoder_deg == 0.01 and n.probe_mm is None


def test_calibration_options_and_data(arm, data):
    with refused(ValueError, match='method = "newton"'):
        aacmm.calibrate(arm, data, method="newton")
    with refused(ValueError, match="fix = theta9: unknown parameter `theta9`"):
        aacmm.calibrate(arm, data, fix="theta9")
    with refused(ValueError, match="cross_validate = 1"):
        aacmm.calibrate(arm, data, cross_validate=1)
    with refused(ValueError, match="^threads = 0: at least 1$"):
        aacmm.calibrate(arm, data, threads=0)
    with refused(ValueError, match="fix"):
        aacmm.calibrate(arm, data, fix=3)
    with refused(ValueError, match='robust = "bogus": one of huber, cauchy'):
        aacmm.calibrate(arm, data, robust="bogus")
    with refused(ValueError, match="^robust_scale = -1: must be a finite number > 0$"):
        aacmm.calibrate(arm, data, robust="huber", robust_scale=-1)
    with refused(ValueError, match=r"^robust_scale = 2: needs a robust loss \(huber or cauchy\)$"):
        aacmm.calibrate(arm, data, robust_scale=2)
    # Nothing fixed: the base rotation is a direction no touch can see.
    with refused(aacmm.CalibrationError, match="directions the data cannot see"):
        aacmm.calibrate(arm, data, fix="", method="lm")
    labels, q = read_poses()
    small = aacmm.DataSet(labels[:3] + labels[10:13], q[:3] + q[10:13], angle_unit="deg")
    with refused(aacmm.CalibrationError, match=r"scale \(no reference length\)"):
        aacmm.calibrate(arm, small, method="lm", fix="theta1,d1,theta6,alpha6,Bx,By")
    with refused(ValueError, match="cross_validate = 50"):
        aacmm.calibrate(arm, data, cross_validate=50)
    arm7 = aacmm.Arm.from_params(7, np.r_[np.full(21, 100.0), np.zeros(7), 0, 0, 50])
    with refused(ValueError, match="^data: the arm has 7 joints, the data 6$"):
        aacmm.calibrate(arm7, data)
    seven = aacmm.DataSet(labels, np.c_[np.radians(q), np.zeros(len(q))])
    with refused(ValueError, match="^validate: the arm has 6 joints, the data 7$"):
        aacmm.calibrate(arm, data, validate=seven)
    with refused(ValueError, match="7 joints but the data has 6"):
        aacmm.evaluate(arm7, data)
    with refused(ValueError, match="7 joints but the data has 6"):
        aacmm.identify(arm7, data)
    with refused(ValueError, match="threads = 0"):
        aacmm.identify(arm, data, threads=0)


def test_simulation_settings(arm, tmp_path):
    with pytest.raises(ValueError, match='errors = "wobbly"'):
        aacmm.simulate(arm, sockets=3, poses=5, seed=1, errors="wobbly")
    with pytest.raises(ValueError, match="error_scale"):
        aacmm.simulate(arm, sockets=3, poses=5, seed=1, error_scale=2.0)
    with pytest.raises(ValueError, match="not both"):
        aacmm.simulate(arm, sockets=3, sockets_file=POSES, poses=5, seed=1)
    with pytest.raises(ValueError, match="give sockets"):
        aacmm.simulate(arm, poses=5, seed=1)
    with pytest.raises(ValueError, match="^poses: "):
        aacmm.simulate(arm, sockets=3, poses=2, seed=1)
    with pytest.raises(ValueError, match="^reference_lengths: "):
        aacmm.simulate(arm, sockets=3, poses=5, seed=1, reference_lengths=9)
    sockets = write(tmp_path, "s.csv", "point,x,y,z\nA,1,2\n")
    with pytest.raises(aacmm.InputError, match=r"s\.csv:2"):
        aacmm.simulate(arm, sockets_file=sockets, poses=5, seed=1)
    with pytest.raises(TypeError):
        aacmm.simulate(arm, 3, 5, 1)


def test_hayati_joint_names(tmp_path, data):
    """A Hayati joint's d-slot is `hbeta<i>` (rad in Python), and `d<i>` of
    that joint is refused rather than fixing β silently."""
    parts = aacmm.Arm.from_file(ARM).to_toml().split("[[joint]]\n")
    parts[2] = 'model = "hayati"\n' + parts[2].replace("alpha = 90.0", "alpha = 0.0").replace(
        "d = 0.0", "hbeta = 0.5"
    )
    hayati = write(tmp_path, "hayati.toml", "[[joint]]\n".join(parts))
    arm = aacmm.Arm.from_file(hayati)
    params = arm.to_dict()
    assert "hbeta2" in params and "d2" not in params
    assert params["hbeta2"] == pytest.approx(np.radians(0.5), rel=1e-15)
    with refused(ValueError, match="joint 2 is a Hayati joint: its d-slot is `hbeta2`"):
        aacmm.calibrate(arm, data, fix="theta1,d2")


def test_one_rule_per_setting(arm, data):
    """The same setting gives the same exception class and bounds in
    identify, calibrate and simulate, and the message names the argument
    the caller gave."""
    # simulate: a setting out of range is a ValueError naming the argument.
    with refused(ValueError, match=r"^poses: at least 3 touches per socket .*got 2$"):
        aacmm.simulate(arm, sockets=3, poses=2, seed=1)
    with refused(ValueError, match="^sockets: at least one socket"):
        aacmm.simulate(arm, sockets=0, poses=5, seed=1)
    with refused(ValueError, match="^error_scale"):
        aacmm.simulate(arm, sockets=3, poses=5, seed=1, errors="random", error_scale=-1)
    # Seeds: one bound (TOML integers) in calibrate and simulate alike.
    top = 2**63 - 1
    with refused(ValueError, match=rf"^seed = {2**64 - 1}: at most {top}"):
        aacmm.calibrate(arm, data, seed=2**64 - 1)
    with refused(ValueError, match=rf"^seed: at most {top} .*got {2**63}$"):
        aacmm.simulate(arm, sockets=3, poses=5, seed=2**63)
    for call in (
        lambda: aacmm.calibrate(arm, data, seed=-1),
        lambda: aacmm.simulate(arm, sockets=3, poses=5, seed=-1),
    ):
        with pytest.raises(OverflowError):
            call()
    # Encoder noise: one cap (180°) in Noise and in simulate.
    with refused(ValueError, match=r"^encoder_deg: σ = 1e308° is more than 180°: beyond half a turn an angle.s σ means nothing \(a real"):
        aacmm.Noise(encoder_deg=1e308)
    with refused(ValueError, match=r"^encoder_noise_deg: σ = 1e308° is more than 180°"):
        aacmm.simulate(arm, sockets=3, poses=5, seed=1, encoder_noise_deg=1e308)
    # Noise whose weights vanish: ValueError in identify and calibrate alike.
    huge = aacmm.Noise(probe_mm=1e300)
    with refused(ValueError, match="not finite") as by_identify:
        aacmm.identify(arm, data, noise=huge)
    with refused(ValueError, match="not finite") as by_calibrate:
        aacmm.calibrate(arm, data, noise=huge, method="lm")
    assert str(by_identify.value).split(": ", 1)[1] == str(by_calibrate.value).split(": ", 1)[1]
    # Messages show what was given.
    with refused(ValueError, match=r"^encoder_deg: encoder and probe noise both 0"):
        aacmm.Noise(encoder_deg=0)
    with refused(ValueError, match=r"^fix = a1,a1: `a1` is listed twice$"):
        aacmm.calibrate(arm, data, fix="a1,a1")
    with refused(ValueError, match=r"^fix = theta1,d1,theta1: `theta1` is listed twice$"):
        aacmm.calibrate(arm, data, fix=["theta1", "d1", "theta1"])
    with refused(ValueError, match=r"^prior = length=nanmm: `length=nanmm`: "):
        aacmm.calibrate(arm, data, prior="length=nanmm")


def test_hostile_counts_give_ordinary_exceptions(arm, data):
    """Every entry point that takes a count, called with 0, a huge or a
    negative one, raises an ordinary exception (no PanicException, which is
    not an Exception, and no wrong result)."""
    hostile = [
        lambda: aacmm.param_names(0),
        lambda: aacmm.param_names(13),
        lambda: aacmm.param_names(2**62),
        lambda: aacmm.param_names(2**64),
        lambda: aacmm.param_names(-1),
        lambda: aacmm.Arm.from_params(0, np.zeros(3)),
        lambda: aacmm.Arm.from_params(2**62, np.zeros(3)),
        lambda: aacmm.Arm.from_params(-6, np.zeros(27)),
        lambda: aacmm.Arm.from_params(6, np.zeros(0)),
        lambda: aacmm.DataSet.from_files(POSES, joints=0),
        lambda: aacmm.DataSet.from_files(POSES, joints=2**62),
        lambda: data.source_of(len(data)),
        lambda: data.source_of(2**64 - 1),
        lambda: data.source_of(-1),
        lambda: arm.positions(np.zeros((3, 0))),
        lambda: arm.jacobians(np.zeros(0)),
        lambda: arm.joint_jacobian(np.zeros((0, 7))),
        lambda: aacmm.DataSet(["A"], np.zeros((1, 0))),
        lambda: aacmm.DataSet([], np.zeros((0, 2**20))),
        lambda: aacmm.identify(arm, data, threads=0),
        lambda: aacmm.calibrate(arm, data, threads=0),
        lambda: aacmm.calibrate(arm, data, cross_validate=0),
        lambda: aacmm.calibrate(arm, data, cross_validate=2**62),
        lambda: aacmm.simulate(arm, sockets=2**62, poses=5, seed=1),
        lambda: aacmm.simulate(arm, sockets=3, poses=2**62, seed=1),
        lambda: aacmm.simulate(arm, sockets=3, poses=0, seed=1),
        lambda: aacmm.simulate(arm, sockets=3, poses=5, seed=1, reference_lengths=2**62),
        lambda: aacmm.simulate(arm, sockets=3, poses=-5, seed=1),
    ]
    for i, call in enumerate(hostile):
        try:
            call()
        except (ValueError, TypeError, OverflowError, IndexError, aacmm.AacmmError) as e:
            assert "internal error" not in str(e), (i, e)
        else:
            pytest.fail(f"hostile call {i} was accepted")
    # The empty arrays of a valid shape are valid: empty results.
    assert arm.positions(np.zeros((0, 6))).shape == (0, 3)
    assert arm.jacobians(np.zeros((0, 6)))[1].shape == (0, 3, 27)


def test_messages_are_bounded(tmp_path, arm, data):
    """A user's text echoed in a message (a label, a token, a value) is cut
    to 80 characters with its length said, and its control characters are
    escaped: a 5 MB label does not make a 5 MB message."""
    huge = "L" * 5_000_000
    labels, q = read_poses()
    with pytest.raises(aacmm.InputError) as caught:
        aacmm.DataSet(labels[:3] + [huge], q[:4], angle_unit="deg")
    message = str(caught.value)
    assert len(message) < 400 and "(5000000 characters)" in message, message[:500]
    # A field the reader takes (its lines stop at 1 MiB) is cut; a line
    # beyond that is refused for its length, unquoted.
    field = "L" * 900_000
    poses = write(tmp_path, "p.csv", "point,q1,q2,q3,q4,q5,q6\n" + "A,1,2,3,4,5,6\n" * 5 + f"A,1,2,{field},4,5,6\n")
    with pytest.raises(aacmm.InputError, match=r":7: field `q3`: `L+…` \(900000 characters\) is not a number$") as caught:
        aacmm.DataSet.from_files(poses)
    assert len(str(caught.value)) < 400
    poses = write(tmp_path, "p.csv", "point,q1,q2,q3,q4,q5,q6\n" + "A,1,2,3,4,5,6\n" * 5 + f"A,1,2,{huge},4,5,6\n")
    with pytest.raises(aacmm.InputError, match=r"p\.csv:7: line longer than 1 MiB") as caught:
        aacmm.DataSet.from_files(poses)
    assert len(str(caught.value)) < 400
    for kwargs, arg in (({"fix": "x" * 1_000_000}, "fix"), ({"prior": "y" * 1_000_000}, "prior")):
        with refused(ValueError, match=rf"^{arg} = \w+… \(1000000 characters\): ") as caught:
            aacmm.calibrate(arm, data, **kwargs)
        assert len(str(caught.value)) < 600, str(caught.value)[:700]
    with refused(ValueError, match=r"unknown parameter `a1\\r\\n\\0`") as caught:
        aacmm.calibrate(arm, data, fix="a1\r\n\0")
    assert "\r" not in str(caught.value) and "\0" not in str(caught.value)


def test_cr_only_line_endings_are_named(tmp_path):
    """A file whose lines end with CR alone is said to be one, rather than
    read as one line whose fields run into each other."""
    text = "point,q1,q2,q3,q4,q5,q6\r" + "A,1,2,3,4,5,6\r" * 5
    poses = write(tmp_path, "mac.csv", "")
    poses.write_bytes(text.encode())
    with pytest.raises(aacmm.InputError, match=r"mac\.csv:1: .*carriage return alone"):
        aacmm.DataSet.from_files(poses)


HOSTILE_SIZES = r"""
import resource, sys
import numpy as np
import aacmm
resource.setrlimit(resource.RLIMIT_AS, (2 << 30, 2 << 30))
arm = aacmm.Arm.from_file(sys.argv[1])
many = np.broadcast_to(np.zeros(6), (3 * 10**8, 6))
calls = {
    "positions": lambda: arm.positions(many),
    "jacobians": lambda: arm.jacobians(many),
    "joint_jacobian": lambda: arm.joint_jacobian(many),
    "DataSet": lambda: aacmm.DataSet(["A"], np.broadcast_to(np.zeros(1000), (10**7, 1000))),
    "from_positions": lambda: aacmm.DataSet.from_positions(many, np.zeros((1, 3))),
}
for name, call in calls.items():
    try:
        call()
        print(name, "accepted")
    except MemoryError as e:
        print(name, "MemoryError", str(e)[:200])
"""


def test_outputs_too_large_are_memory_errors(tmp_path):
    """An output or copy sized by the input that cannot be allocated is a
    MemoryError before any work, as numpy's own, not an abort of the process
    (run in a subprocess under a 2 GiB address-space limit)."""
    import subprocess
    import sys

    done = subprocess.run(
        [sys.executable, "-c", HOSTILE_SIZES, ARM], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    lines = done.stdout.splitlines()
    assert [line.split()[:2] for line in lines] == [
        [name, "MemoryError"]
        for name in ("positions", "jacobians", "joint_jacobian", "DataSet", "from_positions")
    ], done.stdout


HOSTILE_FILES = r"""
import resource, sys
import aacmm
arm_path, endless, big, many = sys.argv[1:5]
def virtual_size():
    with open("/proc/self/status") as f:
        line = next(l for l in f if l.startswith("VmSize:"))
    return int(line.split()[1]) * 1024
arm = aacmm.Arm.from_file(arm_path)
data = aacmm.DataSet.from_files(many)
limit = virtual_size() + (256 << 20)
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
def run(calls):
    for name, call in calls.items():
        try:
            call()
            print(name, "accepted")
        except (MemoryError, aacmm.InputError) as e:
            print(name, type(e).__name__, str(e)[:300])
run({
    "endless": lambda: aacmm.DataSet.from_files(endless),
    "big": lambda: aacmm.DataSet.from_files(big),
})
tight = virtual_size() + (48 << 20)
resource.setrlimit(resource.RLIMIT_AS, (tight, limit))
run({
    "calibrate": lambda: aacmm.calibrate(arm, data, method="lm"),
    "identify": lambda: aacmm.identify(arm, data),
    "evaluate": lambda: aacmm.evaluate(arm, data),
})
"""


def touches(path, rows):
    """A poses file of `rows` valid touches of one point, 14 bytes a row:
    its readings take four times the file once read."""
    path.write_text("point,q1,q2,q3,q4,q5,q6\n" + "A,1,2,3,4,5,6\nA,2,3,4,5,6,7\n" * (rows // 2))
    return path


def test_files_too_large_are_errors_not_aborts(tmp_path):
    """Under an address space 256 MiB above what the process uses: a 1 GiB
    file of one line is refused for its line (read 1 MiB at most); a file
    whose readings need more than the limit is a MemoryError from the
    reader. With 48 MiB left beside a 10⁶-touch data set, its calibration,
    identification and evaluation are MemoryErrors before the work (160,
    96 and 64 bytes a touch) — the process survives each (issue 29)."""
    import subprocess
    import sys

    endless = tmp_path / "endless.csv"
    endless.write_text("point,q1,q2,q3,q4,q5,q6\nA,1")
    with open(endless, "r+b") as f:
        f.truncate(1 << 30)  # sparse: no disk used
    big = touches(tmp_path / "big.csv", 8_000_000)
    many = touches(tmp_path / "many.csv", 1_000_000)
    done = subprocess.run(
        [sys.executable, "-c", HOSTILE_FILES, ARM, str(endless), str(big), str(many)],
        capture_output=True,
        text=True,
        timeout=300,
        env={**os.environ, "MALLOC_ARENA_MAX": "1"},
    )
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    out = done.stdout
    assert "endless InputError" in out and "endless.csv:2: line longer than 1 MiB" in out, out
    assert "big MemoryError" in out and "big.csv: out of memory: the rows' readings" in out, out
    assert "calibrate MemoryError" in out, out
    assert "out of memory: calibrating 1000000 observations and 0 lengths needs" in out, out
    assert "identify MemoryError" in out and "identifying from 1000000 observations" in out, out
    assert "evaluate MemoryError" in out and "evaluating 1000000 observations" in out, out


HELD = r"""
import resource, sys
import aacmm
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
try:
    aacmm.DataSet.from_files(sys.argv[1])
    print("accepted")
except aacmm.InputError as e:
    print("refused", str(e)[:300])
print("held", (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before) * 1024)
"""


def test_a_file_of_a_new_label_per_row_is_held_within_six_times_its_size(tmp_path):
    """A poses file of one-digit readings and a new label on every row
    (10⁶ rows, 21 MB) is refused for its touch counts while the process's
    peak grows by at most 6× the file: the text, the rows (60 bytes each
    from 21), each label once. It was 14.7× before the labels were stored
    once and the articulation check kept a range per point and joint."""
    import subprocess
    import sys

    path = tmp_path / "labels.csv"
    rows = "".join(f"a{i:07d},1,2,3,4,5,6\n" for i in range(10**6))
    path.write_text("point,q1,q2,q3,q4,q5,q6\n" + rows)
    size = path.stat().st_size
    done = subprocess.run(
        [sys.executable, "-c", HELD, str(path)], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    lines = done.stdout.splitlines()
    assert lines[0].startswith("refused") and "point `a0000000` has 1 touch" in lines[0], lines
    held = int(lines[1].split()[1])
    assert held <= 6 * size, (held, size, held / size)


def test_simulation_messages_are_bounded(arm, tmp_path):
    """A socket label or an argument echoed by simulate is cut to 80
    characters with its length said and its control characters escaped:
    a CR/LF/NUL label or a 10 000-character one gives a short message."""
    at = "143.413053,63.660416,861.184613"
    for label in ("S\r\n\0", "S" + "x" * 9_999):
        sockets = tmp_path / "sockets.csv"
        sockets.write_text(f'point,x,y,z\nA,{at}\n"{label}",{at}\n', newline="")
        with refused(ValueError, match=r"^sockets_file: sockets `A` and `S") as caught:
            aacmm.simulate(arm, sockets_file=sockets, poses=3, seed=1)
        messages = [str(caught.value)]
        with refused(ValueError, match=r'^errors = "S') as caught:
            aacmm.simulate(arm, sockets=3, poses=3, seed=1, errors=label)
        messages.append(str(caught.value))
        for m in messages:
            assert len(m) < 600 and not any(c in m for c in "\r\n\0"), m[:700]
            assert len(label) < 10_000 or "(10000 characters)" in m, m


@pytest.mark.parametrize("call", ["calibrate", "identify"])
def test_hostile_thread_counts(arm, data, call):
    """threads: 1 to 1024 in every front end (the command line's --threads
    and C's setter too); a hostile count is a ValueError naming threads,
    never an attempt to start that many workers, and a count beyond a
    machine integer is pyo3's OverflowError, not a panic."""
    run = getattr(aacmm, call)
    for n in (1025, 2**62, 2**64 - 1):
        with refused(ValueError, match=rf"^threads = {n}: at most 1024 worker threads"):
            run(arm, data, threads=n)
    with refused(ValueError, match="^threads = 0: at least 1$"):
        run(arm, data, threads=0)
    for n in (2**64, 2**200, -1):
        with pytest.raises(OverflowError):
            run(arm, data, threads=n)
