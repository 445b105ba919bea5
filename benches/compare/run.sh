#!/usr/bin/env bash
# Ceres against aacmm on the `calibrate-lm` bench's problem
# (benches/calibrate.rs) at 100, 10⁴ and 10⁵ touches: builds the Ceres
# program (needs libceres-dev), writes the campaigns with
# examples/ceres_export.rs, runs Ceres with autodiff and with analytic
# Jacobians, then the criterion benches lm-solve/N (aacmm's LM alone) and
# calibrate-lm/N (the whole calibration), and prints the table.
# Not part of CI. Usage: benches/compare/run.sh [OUT_DIR]   (default target/compare)
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-target/compare}
mkdir -p "$out"
make -s -C benches/compare ceres_lm
cargo build -q --release --example ceres_export
# sockets touches repeats(aacmm) repeats(ceres)
sizes=("10 10 50 50" "100 100 10 10" "1000 100 3 3")
: > "$out/ceres.txt"
for s in "${sizes[@]}"; do
  read -r k t ra rc <<<"$s"
  dir="$out/$((k * t))"
  target/release/examples/ceres_export "$k" "$t" "$dir" "$ra" >/dev/null
  for mode in autodiff analytic; do
    benches/compare/ceres_lm "$dir" "$rc" "$mode" >> "$out/ceres.txt"
  done
done
AACMM_BENCH_LARGE=1 cargo bench -q --bench calibrate -- \
  '^(calibrate-lm|lm-solve)/(100|10000|100000)$' > "$out/criterion.txt" 2>&1
# Criterion's median of ID in ms.
median_ms() {
  awk -v id="$1" '$1 == id && $2 == "time:" { v = $5; u = $6 }
    END { if (u == "µs") v /= 1000; else if (u == "ns") v /= 1e6; else if (u == "s") v *= 1000; print v }' \
    "$out/criterion.txt"
}
# The Ceres run of MODE at N touches: field F of its line.
ceres() {
  awk -v m="$1" -v n="$2" -v f="$3" '$1 == m && $2 == n { print $f }' "$out/ceres.txt"
}
printf '%-8s %11s %11s %10s %12s %9s %9s %9s %12s\n' touches "autodiff ms" "analytic ms" \
  "lm-solve ms" "calibrate ms" "an/solve" "ad/solve" "an/calib" "same minimum"
for n in $(awk '{ print $2 }' "$out/ceres.txt" | uniq); do
  ad=$(ceres autodiff "$n" 4)
  an=$(ceres analytic "$n" 4)
  same=$(ceres analytic "$n" 12)
  solve=$(median_ms "lm-solve/$n")
  whole=$(median_ms "calibrate-lm/$n")
  awk -v n="$n" -v ad="$ad" -v an="$an" -v s="$solve" -v w="$whole" -v same="$same" 'BEGIN {
    printf "%-8s %11.3f %11.3f %10.3f %12.3f %9.1f %9.1f %9.1f %12s\n", n, ad, an, s, w,
      an / s, ad / s, an / w, same }'
done
echo "Ceres ms: Solve alone (the weights and the problem built before it not counted), the"
echo "fastest of its repeats; lm-solve ms: criterion's median of aacmm's LM alone (the normal"
echo "equations at the start and the iterations); calibrate ms: calibrate-lm/N's median (the"
echo "whole calibration: identifiability checks, LM, reweighing, covariance, outliers,"
echo "uncertainty). Ratios: Ceres analytic (an) or autodiff (ad) over lm-solve, and analytic"
echo "over the whole calibration. Same minimum: |Ceres analytic's final cost − aacmm's| /"
echo "aacmm's (the same least squares; autodiff's lengths pull its free centres, so its"
echo "minimum differs: $(awk '$1 == "autodiff" { printf "%s ", $12 }' "$out/ceres.txt"))."
echo "load: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores, $(date -u +%F)"
