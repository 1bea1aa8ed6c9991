#!/bin/bash
# Another sender's trial configurations on the bus (run inside the VM by
# scripts/kernel-vm): while `mjc trial` runs 6° × 3 trials on a simulated board
# (`mjc sim`, subject 1 donned) on vcan0, two cangen processes send node 1 TrialConfig
# frames of their own — one 40° × 5 (what a lab's other tool would send), one of random
# values. A configuration frame names no sender, so only the start naming the host's
# configuration (its digest) and the board's MotionConfig and window starts naming what
# runs keep a trial from running, or being recorded under, another sender's settings.
#
# The reference is physical: a first trial without the other senders gives the peak
# torque of a 6° flexion on this hand (the plant's); 40° gives about eight times more.
# Each flooded trial either completes with exactly its 3 flexions and 3 extensions, each
# flexion's peak torque within a factor of two of the reference, or ends non-zero with
# no window recorded and the reason named. A trial that records a window otherwise is
# mislabelled: counted and printed as ./bench's foreign_config_trials_mislabelled
# (goal 0), and a failure.
# usage: foreign_config.sh <path of mjc>
set -u
mjc=$1
work=$(mktemp -d)
trials=4
fail() { echo "FAIL $*"; tail -n 20 "$work"/*.err 2>/dev/null; exit 1; }
. "$(dirname "$0")/checks.sh"

# The plant's own slack (sim_host/params/default.json), so no sweep is needed.
cat >"$work/cal.json" <<'JSON'
{"c_right_deg": 1.1001, "c_left_deg": -0.8995, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
"$mjc" sim --iface vcan0 --node 1 --subject subject1 2>"$work/sim.err" &
sim=$!
wait_for "$work/sim.err" "mjc sim: node 1 on vcan0" || fail "the simulated board did not come up"
"$mjc" cal upload "$work/cal.json" --iface vcan0 --node 1 >"$work/cal.out" 2>&1 ||
  fail "calibration upload"

run_trial() {  # NAME: a 6° × 3 trial into $work/NAME; its exit status
  "$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 6 --reps 3 \
    --frequency-hz 1 --rest-s 0.2 --out "$work/$1" --no-figure >"$work/$1.out" 2>"$work/$1.err"
}
# windows.csv's flexion peak torques (column peak_torque_Nm), one a line.
flexion_peaks() {
  awk -F, '$1 ~ /^[0-9]+$/ && $4 == "flexion" { print $15 }' "$1/windows.csv" 2>/dev/null
}

run_trial reference || fail "the reference trial (no other sender) exited $?"
reference=$(flexion_peaks "$work/reference" | awk '{ s += $1; n++ } END { if (n == 3) printf "%.6f", s / n }')
[ -n "$reference" ] || fail "the reference trial did not record 3 flexions"
echo "reference flexion peak torque: $reference N.m (6° on subject 1)"

# 0x051: TrialConfig to node 1. 40° (0x00B2B8C2 in Q7.24 rad), 1000 mHz, 5, 0.2 s.
cangen vcan0 -g 1 -I 051 -L 8 -D C2B8B200E8030502 2>"$work/gen1.err" &
gen1=$!
cangen vcan0 -g 3 -I 051 -L 8 -D r 2>"$work/gen2.err" &
gen2=$!
mislabelled=0
completed=0
refused=0
for ((t = 1; t <= trials; t++)); do
  run_trial "t$t"
  status=$?
  peaks=$(flexion_peaks "$work/t$t")
  n=$(echo -n "$peaks" | grep -c .)
  windows=$(awk -F, '$1 ~ /^[0-9]+$/' "$work/t$t/windows.csv" 2>/dev/null | wc -l)
  if [ "$status" = 0 ]; then
    completed=$((completed + 1))
    # Exactly its own windows, each of a 6° flexion.
    off=$(echo "$peaks" | awk -v r="$reference" 'NF && ($1 < r / 2 || $1 > 2 * r) { n++ } END { print n + 0 }')
    if [ "$n" != 3 ] || [ "$windows" != 6 ] || [ "$off" != 0 ]; then
      echo "trial $t: exit 0 with $windows windows, $n flexions, $off off the reference: $peaks"
      mislabelled=$((mislabelled + 1))
    fi
  else
    refused=$((refused + 1))
    if [ "$windows" != 0 ]; then
      echo "trial $t: exit $status yet $windows windows recorded"
      mislabelled=$((mislabelled + 1))
    fi
    # The reason, named: a refused start or a motion that is not the one sent.
    grep -Eq 'holds another configuration|runs a trial of session|began a window of configuration' "$work/t$t.err" ||
      fail "trial $t: exit $status without the reason: $(tail -n 3 "$work/t$t.err")"
  fi
done
kill "$gen1" "$gen2" 2>/dev/null
wait "$gen1" "$gen2" 2>/dev/null
kill -INT "$sim"
wait "$sim"
echo "trials under the flood: $completed completed, $refused refused"
echo "foreign_config_trials_mislabelled: $mislabelled trials (of $trials run while other senders flooded node 1 with TrialConfig frames)"
[ "$mislabelled" = 0 ] || fail "$mislabelled trials recorded under a configuration that did not run"
[ "$completed" -ge 1 ] || fail "no trial completed under the flood"
echo "PASS nothing was recorded under a configuration that did not run"
