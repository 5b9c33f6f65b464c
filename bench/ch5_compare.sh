#!/usr/bin/env bash
# Chapter 5 comparison (thesis Table 5.3): passive, TSS1, TSS2, TSS3 on the lumped quarter car,
# same seeded ISO 8608 class B road at 34 km/h, monolithic mode (same node code, one process),
# one run after the other; then the ride table with % change against passive.
#
#   bash bench/ch5_compare.sh [OUT_DIR]        (default OUT_DIR: runs/ch5_compare)
#
# Extra arguments after OUT_DIR are passed to every run, e.g. --set road.seed=7.
# Wall time on a 2-core machine: about 4 s (passive, TSS1, h = 2 ms) and 15-25 s (TSS2, TSS3,
# h = 0.5 ms) each. Results: docs/ch5_control_comparison.md.
set -euo pipefail
cd "$(dirname "$0")/.."
out="${1:-runs/ch5_compare}"
shift || true
mkdir -p "$out"
for law in passive tss1 tss2 tss3; do
  python -m orchestrator run "scenarios/ch5_qvm_${law}_random.toml" --out "$out/$law" \
    --mode monolithic --quiet "$@" > "$out/$law.log" 2>&1 || { cat "$out/$law.log"; exit 1; }
  grep -E "^run |wall" "$out/$law.log"
done
python -m orchestrator ride "$out/passive" "$out/tss1" "$out/tss2" "$out/tss3" --baseline passive
