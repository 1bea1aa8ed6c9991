#!/bin/sh
# mjc-paper's tables never print a normalised error that means nothing: on a purely
# elastic attachment the net work is ~0 at every amplitude, so its NRMSE (the RMSE over
# the truth's range across amplitudes) is printed as "n/a (range …, within the noise
# floor …)", results.json gives null beside the range and the floor, and the damped
# subject's NRMSE in the same run is still a percentage. The range and the floor are
# recomputed here from results.json's per-amplitude points (sim/scenarios.h,
# EnergyNoiseFloor: 2 SE of the board's means, at least 1 % of the largest loading work).
# Usage: paper_honest_tables.sh MJC_PAPER PARAMS_DIR WORK_DIR
set -u
paper=$1
params=$2
work=$3
rm -rf "$work"
mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

sed -e 's/"damping_Nm_s_per_rad": 0.25/"damping_Nm_s_per_rad": 0.0/' \
  -e 's/"name": "subject1"/"name": "elastic"/' "$params/subject1.json" >"$work/elastic.json"
grep -q '"damping_Nm_s_per_rad": 0.0' "$work/elastic.json" ||
  fail "subject1.json no longer has the damping this test edits"
"$paper" --quiet --scenario amplitude --threads 2 --subjects "$work/elastic.json" \
  subject1 --out "$work/out" >"$work/stdout" 2>"$work/stderr" ||
  fail "mjc-paper failed: $(cat "$work/stderr")"

python3 - "$work/out" <<'PY' || exit 1
import json, sys
out = sys.argv[1]
d = json.load(open(out + "/results.json"))
sweeps = {s["subject"]: s for s in d["amplitude_sweep"]}
if set(sweeps) != {"elastic", "subject1"}:
    sys.exit("FAIL: subjects in results.json: %s" % sorted(sweeps))
for name, s in sweeps.items():
    pts = s["points"]
    floor = max(max(0.01 * abs(p["truth_load_J"]["mean"]) for p in pts),
                max(2 * p[q]["se"] for p in pts for q in ("load_J", "unload_J", "net_J")))
    if abs(floor - s["noise_floor_J"]) > 1e-12:
        sys.exit("FAIL: %s: floor %r, recomputed %r" % (name, s["noise_floor_J"], floor))
    for q in ("load", "unload", "net"):
        values = [p["truth_%s_J" % q]["mean"] for p in pts]
        rng = max(values) - min(values)
        if abs(rng - s["range_J"][q]) > 1e-12:
            sys.exit("FAIL: %s %s: range %r, recomputed %r" % (name, q, s["range_J"][q], rng))
        judged = s["nrmse_pct"][q] is not None
        if judged != (rng > floor):
            sys.exit("FAIL: %s %s: range %.3g J against floor %.3g J, NRMSE %r"
                     % (name, q, rng, floor, s["nrmse_pct"][q]))
        print("%s %s: range %.4f mJ, floor %.4f mJ, NRMSE %s"
              % (name, q, rng * 1e3, floor * 1e3, s["nrmse_pct"][q]))
if sweeps["elastic"]["nrmse_pct"]["net"] is not None:
    sys.exit("FAIL: the elastic attachment's net work was normalised")
if sweeps["subject1"]["nrmse_pct"]["net"] is None:
    sys.exit("FAIL: subject1's net work was not normalised")
PY

# The table says why, in the elastic row's net column; no percentage of thousands.
row=$(grep '^| elastic |' "$work/out/tables.md" | head -1)
case $row in
  *"| n/a (range "*" mJ, within the noise floor "*" mJ) |") echo "table: $row" ;;
  *) fail "the elastic row of Tables II–III: $row" ;;
esac
grep -q '^| subject1 | .* | [0-9.]*% |$' "$work/out/tables.md" ||
  fail "subject1's row lost its NRMSE: $(grep '^| subject1 |' "$work/out/tables.md")"
echo "PASS"
