"""Calibrate the shipped UR5 against its laser-tracker positions from Python
(examples/ur5-tracker: Jacobi, MIT): train on the 1000 grid poses, test on
the 20 random ones, as the example's README does with ``aacmm calibrate
--positions ... --validate-positions ...``. Run from the repository root
after ``pip install ./python``:

    python python/examples/tracker_calibration.py

Prints the fitted tracker frame (the registration ``y = R p + t`` fitted
with the arm), the 3-D errors before and after on both sets, and the same
calibration again from arrays (the rows as numpy arrays, e.g. straight from
a tracker's software), which gives the same arm.
"""

import numpy as np

import aacmm

folder = "examples/ur5-tracker"
nominal = aacmm.Arm.from_file(f"{folder}/arm.toml")
train = aacmm.DataSet.from_files(positions=f"{folder}/positions-grid.csv")
test = aacmm.DataSet.from_files(positions=f"{folder}/positions-random.csv")
print(nominal)
print(train)

# %% Calibrate: the tracker's noise is not stated, so the fit estimates it.
cal = aacmm.calibrate(nominal, train, validate=test)
s = cal.summary
print(f"\n{cal}\nsuccessful: {cal.successful}; position σ {s['touch_sigma_mm']:.4f} mm (estimated)")

# %% The tracker frame, with its standard uncertainties (k = 1).
for name, frame in cal.frames.items():
    print(f"\nframe {name!r}:")
    print("  rotation vector, deg:", np.array2string(frame["rotation_deg"], precision=5))
    print("  σ of small rotations about its x, y, z axes, deg:",
          np.array2string(frame["small_rotation_sigma_deg"], precision=5))
    print("  translation, mm:    ", np.array2string(frame["translation_mm"], precision=4))
    print("              σ, mm:  ", np.array2string(frame["translation_sigma_mm"], precision=4))

# %% 3-D errors |R p + t - y| at the positions, before and after, mm.
print("\n                     poses     mean      RMS      max")
for label, figures in (("grid (fitted)", s["fitted"]), ("random (held out)", s["held_out"])):
    for when in ("before", "after"):
        p = figures[when]["positions"]
        print(f"  {label:<17} {when:<6} {p['count']:>4} {p['mean']:8.4f} {p['rms']:8.4f} {p['max']:8.4f}")

# %% The same rows as arrays: the same calibration.
rows = train.positions
arrays = aacmm.DataSet.from_positions(rows["q"], rows["xyz"], labels=rows["labels"])
again = aacmm.calibrate(nominal, arrays)
print(f"\nfrom arrays: largest parameter difference {np.abs(again.params - cal.params).max():.1e}")
