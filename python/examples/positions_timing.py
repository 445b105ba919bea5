"""Batch positions of 10^6 poses from Python (``arm.positions``) against the
same batch in Rust (``PreparedPoses::new`` + ``ArmKernel::positions``: the
Rust side of ``capi/examples/positions_timing.rs``), alternating, each side a
fresh process. Run from the repository root after ``pip install ./python``:

    cargo build --release -p aacmm-capi --example positions_timing
    python python/examples/positions_timing.py

Prints per side the median and the fastest wall-clock call and the processor
time per call (the steadiest figure on a loaded machine), and the
Python/Rust ratios. The Python side returns a new n × 3 array per call (the
API's contract); the Rust side refills one buffer. A timing, not a test.
"""

import os
import statistics
import subprocess
import sys
import time

POSES = 1_000_000
REPS = 15
ROUNDS = 5
RUST = os.path.join("target", "release", "examples", "positions_timing")


def python_child(n, reps):
    import numpy as np

    import aacmm

    i = np.arange(n * 6, dtype=np.float64)
    q = (3.0 * np.sin(0.37 * i + 0.1)).reshape(n, 6)
    arm = aacmm.Arm.from_file("examples/paper-table-1.toml")
    p = arm.positions(q)
    times, checksum = [], 0.0
    cpu0 = time.thread_time_ns()
    for _ in range(reps):
        t0 = time.perf_counter_ns()
        p = arm.positions(q)
        times.append(time.perf_counter_ns() - t0)
        checksum += p[0, 0] + p[-1, -1]
    cpu = (time.thread_time_ns() - cpu0) / reps
    print(f"python_positions {n} {statistics.median(times):.0f} {min(times):.0f} {cpu:.0f} {checksum:.17}")


def side(cmd):
    out = subprocess.run(cmd + [str(POSES), str(REPS)], check=True, capture_output=True, text=True)
    median, fastest, cpu = (float(v) for v in out.stdout.split()[2:5])
    return median, fastest, cpu


def main():
    if len(sys.argv) == 4 and sys.argv[1] == "--python":
        return python_child(int(sys.argv[2]), int(sys.argv[3]))
    if not os.path.exists(RUST):
        sys.exit(f"{RUST} not found: cargo build --release -p aacmm-capi --example positions_timing")
    py, rust = [], []
    for _ in range(ROUNDS):
        py.append(side([sys.executable, __file__, "--python"]))
        rust.append(side([RUST, "--rust"]))

    def summary(t):
        return (
            statistics.median(x[0] for x in t),
            min(x[1] for x in t),
            statistics.median(x[2] for x in t),
        )

    p, r = summary(py), summary(rust)
    print(f"batch positions, 10^6 poses, {ROUNDS} rounds x {REPS} calls per side:")
    print("                 Python      Rust      Python/Rust")
    for name, a, b in zip(("median wall", "fastest wall", "cpu per call"), p, r):
        print(f"  {name:<13} {a / 1e6:>8.1f} ms {b / 1e6:>8.1f} ms  {a / b:>6.3f}")


if __name__ == "__main__":
    main()
