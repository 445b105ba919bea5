"""The shipped campaign's calibration from Python (``aacmm.calibrate``)
against the command line (``aacmm calibrate``, release build), with the
README's settings (``--encoder-noise 0.005 --probe-noise 0.01
--cross-validate 3``). Run from the repository root after ``pip install
./python``:

    cargo build --release --bin aacmm
    python python/examples/calibration_timing.py

Compares like with like: the command line's own account of its work
(``timing.json``: ``fit_ms``, the fit, and ``total_ms``, fit plus validation
and cross-validation, without reading files or writing the report) against
``aacmm.calibrate`` timed around the call (fit, validation, cross-validation
and the report's JSON; without cross-validation for the "fit" row, which
so also counts the validation on the fitted data), 31 alternating runs
each, median and fastest. A timing, not a test.
"""

import json
import os
import statistics
import subprocess
import tempfile
import time

import aacmm

RUNS = 31
CLI = os.path.join("target", "release", "aacmm")
ARGS = [
    "--arm", "examples/paper-table-1.toml",
    "--data", "examples/paper-campaign/poses.csv",
    "--lengths", "examples/paper-campaign/lengths.csv",
    "--encoder-noise", "0.005", "--probe-noise", "0.01", "--cross-validate", "3", "--threads", "1",
]


def main():
    arm = aacmm.Arm.from_file("examples/paper-table-1.toml")
    data = aacmm.DataSet.from_files(
        "examples/paper-campaign/poses.csv", "examples/paper-campaign/lengths.csv"
    )
    noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
    py_fit, py_total, cli_fit, cli_total = [], [], [], []
    with tempfile.TemporaryDirectory() as out:
        for _ in range(RUNS):
            t0 = time.perf_counter()
            aacmm.calibrate(arm, data, noise=noise, threads=1)
            py_fit.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            cal = aacmm.calibrate(arm, data, noise=noise, cross_validate=3, threads=1)
            py_total.append(time.perf_counter() - t0)
            subprocess.run([CLI, "calibrate", *ARGS, "--out", out], check=True, capture_output=True)
            timing = json.load(open(os.path.join(out, "timing.json")))
            cli_fit.append(timing["fit_ms"] / 1e3)
            cli_total.append(timing["total_ms"] / 1e3)
        same = cal.to_json() == open(os.path.join(out, "calibration.json")).read()
    print(f"shipped campaign, {RUNS} runs each (calibration.json identical: {same}):")
    print("                                 Python        CLI    Python/CLI")
    for name, a, b in (("fit", py_fit, cli_fit), ("fit + validation", py_total, cli_total)):
        for how, f in (("median", statistics.median), ("fastest", min)):
            x, y = f(a) * 1e3, f(b) * 1e3
            print(f"  {name + ', ' + how:<28} {x:>8.2f} ms {y:>8.2f} ms  {x / y:>6.3f}")


if __name__ == "__main__":
    main()
