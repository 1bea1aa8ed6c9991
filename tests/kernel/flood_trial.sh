#!/bin/bash
# A trial while the bus is flooded (run inside the VM by scripts/kernel-vm): a
# simulated board (`mjc sim`, subject 1 donned) runs `mjc trial` on vcan0 while two
# cangen processes flood the bus as fast as the kernel lets them, one with truncated
# setpoints for the board (malformed), one with another board's telemetry (ignored).
# Every window must reach the host, the board must not fault, and every flood frame must
# be accounted for: counted malformed (a truncated one) or ignored (the other board's) by
# the board, or counted dropped by the kernel on the way in; nothing dropped on the way
# out. How many the kernel drops is a figure, not a verdict: it depends on how much CPU
# the generators leave the board, which is the machine's speed (at the kernel layer's 3x
# slow-down the board ran at a third of real time and the kernel dropped a quarter).
# Prints the two as ./bench's vm_flood_frames_dropped and vm_flood_frames_per_s lines.
# usage: flood_trial.sh <path of mjc>
set -u
mjc=$1
work=$(mktemp -d)
frames=20000
fail() { echo "FAIL $*"; tail -n 20 "$work"/*.err "$work"/*.out 2>/dev/null; exit 1; }
. "$(dirname "$0")/checks.sh"
. "$(dirname "$0")/receivers.sh"
# Frames the input backlog drops count as the kernel's drops (receivers.sh).
backlog_before=$(backlog_dropped)

# The plant's own slack (sim_host/params/default.json), so no sweep is needed.
cat >"$work/cal.json" <<'JSON'
{"c_right_deg": 1.1001, "c_left_deg": -0.8995, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
"$mjc" sim --iface vcan0 --node 1 --subject subject1 2>"$work/sim.err" &
sim=$!
wait_for "$work/sim.err" "mjc sim: node 1 on vcan0" || fail "the simulated board did not come up"
"$mjc" cal upload "$work/cal.json" --iface vcan0 --node 1 >"$work/cal.out" 2>&1 ||
  fail "calibration upload"

start=$(date +%s.%N)
cangen vcan0 -g 0 -I 031 -L 3 -D i -n "$frames" 2>"$work/gen1.err" &  # setpoint, 3 of 6 bytes
gen1=$!
cangen vcan0 -g 0 -I 202 -L 8 -D i -n "$frames" 2>"$work/gen2.err" &  # node 2's angles
gen2=$!
"$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 3 \
  --frequency-hz 2 --rest-s 0.2 --out "$work/trial" --no-figure >"$work/trial.out" 2>"$work/trial.err" ||
  fail "mjc trial under the flood"
wait "$gen1" "$gen2"
end=$(date +%s.%N)
# Every flood frame in the board's socket before it stops (a generator that has exited
# may have frames still in the kernel's backlog; receivers.sh): on SIGINT the board
# handles what its socket holds. The marker is one more frame the board ignores.
why=$(flush_bus) || fail "$why"
kill -INT "$sim"
wait "$sim"

flex=$(grep -c ',flexion,' "$work/trial/windows.csv")
ext=$(grep -c ',extension,' "$work/trial/windows.csv")
[ "$flex" -eq 3 ] && [ "$ext" -eq 3 ] || fail "windows: $flex flexions, $ext extensions"
grep -q 'fault' "$work/trial.err" && fail "the board faulted"
summary=$(grep 'simulated' "$work/sim.err")
echo "$summary"
field() { echo "$summary" | sed -n "s/.*$1 \\([0-9]*\\).*/\\1/p"; }
malformed=$(field malformed)
ignored=$(field ignored)
rx_dropped=$(field 'rx dropped')
backlog=$(($(backlog_dropped) - backlog_before))
tx_dropped=$(field 'tx dropped')
echo "vm_flood_frames_dropped: $((rx_dropped + backlog + tx_dropped)) frames (of 2 x $frames flood frames; rx $rx_dropped, input backlog $backlog, tx $tx_dropped)"
# At most: the flood's frames and the bus marker (counted malformed or ignored, if the
# board's filters let it in).
[ "$malformed" -le $((frames + 1)) ] || fail "malformed $malformed, more than the $frames sent and the marker"
[ "$ignored" -le $((frames + 1)) ] || fail "ignored $ignored, more than the $frames of another board's and the marker"
# At least: the kernel's drops (at the board's socket, in the input backlog) may
# include host frames and the marker.
[ $((malformed + ignored + rx_dropped + backlog)) -ge $((2 * frames)) ] ||
  fail "malformed $malformed + ignored $ignored + dropped by the kernel $rx_dropped at the socket, $backlog in the input backlog: fewer than the $((2 * frames)) sent"
[ "$tx_dropped" = 0 ] || fail "tx dropped $tx_dropped"
awk -v s="$start" -v e="$end" -v n="$frames" \
  'BEGIN { printf "vm_flood_frames_per_s: %.0f frames/s (2 x %d frames in %.2f s, during the trial)\n", 2 * n / (e - s), n, e - s }'
echo "PASS every window arrived and every flood frame was accounted for"
