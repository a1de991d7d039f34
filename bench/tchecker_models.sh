#!/bin/sh
# Generate the TChecker models of bench/tchecker_bench.py with TChecker's own generator scripts.
#
#   bench/tchecker_models.sh EXAMPLES_DIR OUT_DIR
#
# EXAMPLES_DIR is examples/ of a TChecker source tree (fischer.sh, csmacd.sh, fddi.sh, dining-philosophers.sh);
# OUT_DIR receives one .tck file per model and must lie outside this repository (third-party models are never
# committed). Sizes: Fischer 6 to 10 (TChecker's default K=10), CSMA/CD, FDDI and dining philosophers 3 to 5 and
# 7 (their default constants).
set -eu
if [ $# -ne 2 ]; then
    echo "usage: $0 EXAMPLES_DIR OUT_DIR" >&2
    exit 2
fi
EX=$1
OUT=$2
for script in fischer.sh csmacd.sh fddi.sh dining-philosophers.sh; do
    if [ ! -f "$EX/$script" ]; then
        echo "$0: $EX/$script not found: give examples/ of a TChecker source tree" >&2
        exit 2
    fi
done
REPO=$(cd "$(dirname "$0")/.." && pwd)
PARENT=$(cd "$(dirname "$OUT")" && pwd)
case "$PARENT/$(basename "$OUT")/" in
    "$REPO"/*) echo "$0: $OUT is inside the repository: generate the models elsewhere" >&2; exit 2 ;;
esac
mkdir -p "$OUT"
for n in 6 7 8 9 10; do bash "$EX/fischer.sh" "$n" > "$OUT/fischer_$n.tck"; done
for n in 3 4 5 7; do
    bash "$EX/csmacd.sh" "$n" > "$OUT/csmacd_$n.tck"
    bash "$EX/fddi.sh" "$n" > "$OUT/fddi_$n.tck"
    bash "$EX/dining-philosophers.sh" "$n" > "$OUT/dining_philosophers_$n.tck"
done
ls "$OUT"/*.tck
