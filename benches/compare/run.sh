#!/usr/bin/env bash
# Ceres against aacmm on the `lm` bench's problem (benches/calibrate.rs) at
# 100, 10⁴ and 10⁵ touches: builds the Ceres program (needs libceres-dev),
# writes the campaigns with examples/ceres_export.rs, runs both, then the
# criterion benches lm/100, lm/10000, lm/100000, and prints the ratio table.
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
  benches/compare/ceres_lm "$dir" "$rc" >> "$out/ceres.txt"
done
AACMM_BENCH_LARGE=1 cargo bench -q --bench calibrate -- '^lm/(100|10000|100000)$' \
  > "$out/criterion.txt" 2>&1
# Criterion's median of lm/N in ms.
median_ms() {
  awk -v id="lm/$1" '$1 == id && $2 == "time:" { v = $5; u = $6 }
    END { if (u == "µs") v /= 1000; else if (u == "ns") v /= 1e6; else if (u == "s") v *= 1000; print v }' \
    "$out/criterion.txt"
}
printf '%-8s %10s %10s %7s %12s %7s %11s %11s %9s\n' touches "Ceres ms" "aacmm ms" ratio \
  "criterion ms" ratio "max Δ mm" "max Δ rad" "same cost"
while read -r n ctot csolve ams ccost acost it dmm drad same; do
  crit=$(median_ms "$n")
  r1=$(awk -v a="$ctot" -v b="$ams" 'BEGIN { printf "%.1f", a / b }')
  r2=$(awk -v a="$ctot" -v b="$crit" 'BEGIN { printf "%.1f", a / b }')
  printf '%-8s %10.3f %10.3f %7s %12.3f %7s %11s %11s %9s\n' "$n" "$ctot" "$ams" "$r1" "$crit" "$r2" \
    "$dmm" "$drad" "$same"
done < "$out/ceres.txt"
echo "Ceres ms: weights, problem and Solve, the fastest of its repeats; aacmm ms: calibrate()"
echo "in ceres_export, the fastest of its repeats; criterion ms: lm/N's median; ratios: Ceres ms"
echo "over each. max Δ: largest parameter difference (lengths, angles; Ceres' centres are pulled"
echo "by the lengths, aacmm's are centroids); same cost: |Σr² of Ceres' problem at aacmm's"
echo "solution − aacmm's cost| / aacmm's cost (the same least squares when ~1e-12)."
echo "load: $(cut -d' ' -f1-3 /proc/loadavg), $(nproc) cores, $(date -u +%F)"
