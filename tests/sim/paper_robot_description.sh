#!/bin/sh
# mjc-paper --robot-description: a bad description is refused before anything runs (one
# line on stderr, exit non-zero, no output folder); a description that is not the
# plant's joint is reported by the calibration scenario, both what the board's sweep
# sees (a cable whose α is not the described one) and what only the simulator knows
# (a spring rate other than the plant's); and the α = 1.25 example joint, described and
# simulated from robots/example-alpha-1.25.json, reproduces the plant's truth within the
# default joint's bounds (tests/sim/paper_scenarios_test.cc: window energies within
# 2 % of the loading work, η within 1 point, the fitted slack within 0.05°), checked in
# results.json, which names the description.
# Usage: paper_robot_description.sh MJC_PAPER ROBOTS_DIR WORK_DIR
set -u
paper=$1
robots=$2
work=$3
rm -rf "$work"
mkdir -p "$work"
fail() { echo "FAIL: $*"; exit 1; }

# Bad descriptions: refused in one line naming the reason, nothing written.
sed 's/"rate_N_per_m": 3150.0/"rate_N_per_m": 5.0/' "$robots/maestro-default.json" \
  >"$work/soft.json"
sed 's/"zero_count": 0/"zero_cont": 0/' "$robots/maestro-default.json" >"$work/typo.json"
printf '{ "name": "x",' >"$work/cut.json"
for bad in soft.json typo.json cut.json missing.json; do
  if msg=$("$paper" --quiet --out "$work/out-$bad" --robot-description "$work/$bad" \
    2>&1 >/dev/null); then
    fail "$bad was accepted"
  fi
  lines=$(printf '%s\n' "$msg" | wc -l)
  [ "$lines" -eq 1 ] || fail "$bad: $lines lines on stderr: $msg"
  case $msg in
    "mjc-paper: robot description refused: "*"$bad"*) echo "refused: $msg" ;;
    *) fail "$bad: unexpected message: $msg" ;;
  esac
  [ ! -e "$work/out-$bad" ] || fail "$bad: an output folder was made"
done
# A joint whose travel the paper's motions leave: refused the same way.
sed 's/"flexion_deg": 75.0/"flexion_deg": 30.0/' "$robots/example-alpha-1.25.json" \
  >"$work/short.json"
if msg=$("$paper" --quiet --out "$work/out-short" --robot-description "$work/short.json" \
  2>&1 >/dev/null); then
  fail "a travel of 30° was accepted for α 1.25 at 30°"
fi
[ "$(printf '%s\n' "$msg" | wc -l)" -eq 1 ] || fail "short travel: $msg"
case $msg in *"beyond its travel"*) echo "refused: $msg" ;; *) fail "short: $msg" ;; esac

# The α = 1.25 joint described, the plant the default one: the board's sweep sees it
# (its fit with the described α is refused for its residual: exit 2).
"$paper" --quiet --scenario calibration --threads 1 --out "$work/alpha" \
  --robot default --robot-description "$robots/example-alpha-1.25.json" \
  >/dev/null 2>"$work/alpha.err"
rc=$?
[ $rc -eq 2 ] || fail "the α mismatch run ended $rc: $(cat "$work/alpha.err")"
grep -q "the calibration sweep does not fit α\|the calibration sweep fits α" \
  "$work/alpha.err" || fail "the α mismatch was not reported: $(cat "$work/alpha.err")"
grep -q "warning.*the calibration sweep" "$work/alpha/tables.md" ||
  fail "the α mismatch is not in tables.md"

# The default joint described with a spring 20 % stiffer than the plant's.
sed 's/"rate_N_per_m": 3150.0/"rate_N_per_m": 3780.0/' "$robots/maestro-default.json" \
  >"$work/stiff.json"
"$paper" --quiet --scenario calibration --threads 1 --out "$work/stiff" \
  --robot default --robot-description "$work/stiff.json" \
  >/dev/null 2>"$work/stiff.err" || fail "the spring mismatch run failed"
grep -q "not the plant's joint (spring rate k" "$work/stiff.err" ||
  fail "the spring mismatch was not reported: $(cat "$work/stiff.err")"
if grep -q "the calibration sweep" "$work/stiff.err"; then
  fail "the cable of the right α was reported as not described: $(cat "$work/stiff.err")"
fi

# The α = 1.25 joint described and simulated: the plant's truth within the bounds.
"$paper" --quiet --scenario amplitude --subjects subject1 --threads 2 \
  --out "$work/example" --robot-description "$robots/example-alpha-1.25.json" \
  >/dev/null 2>"$work/example.err" || fail "the example joint's run failed: $(cat "$work/example.err")"
if grep -q warning "$work/example.err"; then
  fail "warnings on the described joint: $(cat "$work/example.err")"
fi
/usr/bin/python3 - "$work/example/results.json" "$robots/example-alpha-1.25.json" <<'PY' || exit 1
import json, sys
r = json.load(open(sys.argv[1]))
ok = True
def check(what, value, bound):
    global ok
    print(f"{what} {value:.4f} (bound {bound})")
    if not abs(value) <= bound:
        ok = False
check("window energy error %", r["fidelity"]["window_energy_err_pct"], 2.0)
check("eta error points", r["fidelity"]["eta_err_pt"], 1.0)
check("c_r error deg", r["calibration"]["error_right_deg"], 0.05)
check("c_l error deg", r["calibration"]["error_left_deg"], 0.05)
if r["robot"]["path"] != sys.argv[2] or r["robot"]["description"] != json.load(open(sys.argv[2])):
    print("results.json does not name the description"); ok = False
if r["robot"]["plant_differs"]:
    print("plant differs:", r["robot"]["plant_differs"]); ok = False
sys.exit(0 if ok else 1)
PY
grep -q "example-alpha-1.25" "$work/example/tables.md" || fail "tables.md does not name it"
echo "ok"
