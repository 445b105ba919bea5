"""What the tests share: the repository's paths and the command line `aacmm`,
whose outputs the Python results are checked against."""

import os
import pathlib
import subprocess
import sys
import threading
import time

import pytest

import aacmm

REPO = pathlib.Path(__file__).resolve().parents[2]
ARM = "examples/paper-table-1.toml"
POSES = "examples/paper-campaign/poses.csv"
LENGTHS = "examples/paper-campaign/lengths.csv"


@pytest.fixture(autouse=True)
def in_repo(monkeypatch):
    """Every test runs from the repository root, like the README's examples,
    so that file names in messages and reports are the same as the CLI's."""
    monkeypatch.chdir(REPO)


@pytest.fixture(scope="session")
def cli():
    """Runs the command line `aacmm` (AACMM_CLI, or target/debug/aacmm, built
    with cargo when missing) and returns its standard output."""
    exe = os.environ.get("AACMM_CLI")
    if exe is None:
        exe = str(REPO / "target" / "debug" / "aacmm")
        if not os.path.exists(exe):
            subprocess.run(["cargo", "build", "--bin", "aacmm"], cwd=REPO, check=True)

    def run(*args):
        done = subprocess.run(
            [exe, *map(str, args)], cwd=REPO, check=True, capture_output=True, text=True
        )
        return done.stdout

    return run


@pytest.fixture
def arm():
    return aacmm.Arm.from_file(ARM)


@pytest.fixture
def data():
    return aacmm.DataSet.from_files(POSES, LENGTHS)


def read_poses(path=POSES):
    """The labels and readings (as written, degrees) of a poses file."""
    lines = (REPO / path).read_text().splitlines()[1:]
    labels = [line.split(",")[0] for line in lines]
    q = [[float(v) for v in line.split(",")[1:]] for line in lines]
    return labels, q


def read_lengths(path=LENGTHS):
    lines = (REPO / path).read_text().splitlines()[1:]
    return [(a, b, float(d)) for a, b, d in (line.split(",") for line in lines)]


def longest_stall(call):
    """Runs `call()` while another thread ticks; returns (seconds the call took,
    longest gap between ticks). A call that holds the GIL stalls the ticker for
    its whole length; one that releases it leaves gaps of about the switch
    interval, set short here so the test does not depend on the machine's speed."""
    gaps, stop, running = [], threading.Event(), threading.Event()

    def tick():
        last = time.perf_counter()
        while not stop.is_set():
            now = time.perf_counter()
            if running.is_set():
                gaps.append(now - last)
            last = now

    interval = sys.getswitchinterval()
    sys.setswitchinterval(0.0005)
    ticker = threading.Thread(target=tick)
    ticker.start()
    try:
        running.set()
        start = time.perf_counter()
        call()
        took = time.perf_counter() - start
        running.clear()
    finally:
        stop.set()
        ticker.join()
        sys.setswitchinterval(interval)
    return took, max(gaps, default=float("inf"))
