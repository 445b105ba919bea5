"""Calibrate the shipped campaign from Python, notebook style, and plot the
paper's Fig. 6 (single-point error e per point, before and after) when
matplotlib is installed. Run from the repository root after
``pip install ./python`` (and ``pip install matplotlib`` for the figure):

    python python/examples/calibrate_campaign.py [OUT_DIR]

The same calibration as the README's main command (``aacmm calibrate
--encoder-noise 0.005 --probe-noise 0.01 --cross-validate 3``); OUT_DIR
(default ``target/python-example``) receives the command line's files
(calibrated.toml, calibration.json, timing.json, report.html and its figures)
and fig6.png.
"""

import pathlib
import sys
import time

import numpy as np

import aacmm

out = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "target/python-example")
out.mkdir(parents=True, exist_ok=True)

# %% The nominal arm and the campaign: 10 sockets touched 10 times, 5 lengths.
nominal = aacmm.Arm.from_file("examples/paper-table-1.toml")
data = aacmm.DataSet.from_files(
    "examples/paper-campaign/poses.csv", "examples/paper-campaign/lengths.csv"
)
print(nominal)
print(data)

# %% Calibrate: the noise as the campaign was simulated, 3-fold cross-validation.
noise = aacmm.Noise(encoder_deg=0.005, probe_mm=0.01)
start = time.perf_counter()
cal = aacmm.calibrate(nominal, data, noise=noise, cross_validate=3)
took = time.perf_counter() - start
s = cal.summary
print(
    f"{s['method']}: {s['stop_text']} after {s['iterations']} iterations "
    f"({took * 1e3:.1f} ms); {s['free_parameters']} free parameters, "
    f"sigma0 = {s['sigma0']:.3f}"
)
print("fixed:", ", ".join(f"{k} ({v})" for k, v in cal.fixed.items()))

# %% The corrections, with their uncertainties (mm, or degrees for angles).
names = aacmm.param_names(nominal.joints)
angles = np.array([n.startswith(("alpha", "theta")) for n in names])
to_user = np.where(angles, 180 / np.pi, 1.0)
correction = (cal.params - nominal.params) * to_user
sigma = cal.sigma * to_user
for n, c, u in zip(names, correction, sigma):
    if not np.isnan(u):
        print(f"  {n:<7} {c:+10.4f} ± {u:.4f} {'deg' if n.startswith(('alpha', 'theta')) else 'mm'}")

# %% Before and after: the paper's single-point error e per point.
before = aacmm.evaluate(nominal, data)
after = aacmm.evaluate(cal.arm, data)
e_before = np.array([p["e"] for p in before["points"]])
e_after = np.array([p["e"] for p in after["points"]])
print(f"e mean: {e_before.mean():.4f} mm -> {e_after.mean():.4f} mm")
for fold in s["cross_validation"]:
    f = fold["figures"]
    print(
        f"  held out {','.join(fold['held_out'])}: e mean "
        f"{f['before']['e_mean']:.4f} -> {f['after']['e_mean']:.4f} mm"
    )

written = cal.write(out)
print(f"wrote {len(written)} files into {out} (as aacmm calibrate --out)")

# %% Fig. 6, if matplotlib is there.
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: no figure (pip install matplotlib)")
else:
    x = np.arange(len(data.points))
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    top.bar(x, e_before, color="0.6")
    top.axhline(e_before.mean(), ls="--", color="0.3")
    top.set_ylabel("e before, mm")
    bottom.bar(x, e_after * 1e3, color="tab:blue")
    bottom.axhline(e_after.mean() * 1e3, ls="--", color="tab:blue")
    bottom.set_ylabel("e after, µm")
    bottom.set_xticks(x, data.points)
    bottom.set_xlabel("point")
    fig.suptitle("Single-point error e per point (paper Fig. 6), dashed: mean")
    fig.tight_layout()
    fig.savefig(out / "fig6.png", dpi=100)
    print(f"wrote {out / 'fig6.png'}")
