#!/usr/bin/env python3
"""Converts Jacobi's UR5 laser-tracker files (original/, unchanged) into the
toolkit's reference-positions format: `point,q1..q6,x,y,z` with the position
the tracker measured, target + difference (x_t + x_dif, ...; mm, in the
robot's base frame as the data set registered it), joints in degrees as
recorded. Run from this directory: `python3 convert.py`."""
import csv

FILES = [
    ("original/3D_UR5_uncalibrated_grid_cleaned.csv", "positions-grid.csv"),
    ("original/3D_UR5_uncalibrated_random_cleaned.csv", "positions-random.csv"),
]

for source, target in FILES:
    with open(source, newline="") as f:
        rows = list(csv.DictReader(f))
    with open(target, "w", newline="") as out:
        out.write("point," + ",".join(f"q{j}" for j in range(1, 7)) + ",x,y,z\n")
        for r in rows:
            q = [r[f"joint_{j}"] for j in range(1, 7)]
            xyz = [repr(float(r[f"{c}_t"]) + float(r[f"{c}_dif"])) for c in "xyz"]
            out.write(f"T{r['step_order']}," + ",".join(q + xyz) + "\n")
