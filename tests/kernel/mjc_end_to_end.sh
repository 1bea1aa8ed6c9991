#!/bin/bash
# mjc end to end on Debian's CAN stack (run inside the VM by scripts/kernel-vm): a
# simulated board (`mjc sim`) on vcan0, `mjc log` recording, `mjc calibrate` running the
# sweep, the fit and the ISO-TP upload over the bus; can-utils reading our log and
# talking to the board; refusals with reasons and non-zero exits.
# usage: mjc_end_to_end.sh <path of mjc>
set -u
mjc=$1
work=$(mktemp -d)
passed=0
failed=0
check() {  # check <description> <command...>
  local what=$1
  shift
  if "$@" >>"$work/check.log" 2>&1; then
    echo "PASS $what"
    passed=$((passed + 1))
  else
    echo "FAIL $what"
    failed=$((failed + 1))
  fi
}

"$mjc" sim --iface vcan0 --node 1 --speed 4 --seconds 120 2>"$work/sim.err" &
sim=$!
# A second board, with a subject's hand donned, for the trial.
"$mjc" sim --iface vcan0 --node 2 --subject subject1 --speed 4 --seconds 120 2>"$work/sim2.err" &
sim2=$!
"$mjc" log --iface vcan0 --seconds 4 --out "$work/bus.log" 2>"$work/log.err" &
logger=$!
sleep 0.5

check "mjc calibrate: sweep, fit, upload over the bus" \
  "$mjc" calibrate --iface vcan0 --node 1 --frequency-hz 2 --cycles 6 --out "$work/cal.json"
# The plant's slack is c_r 1.1°, c_l -0.9° (sim_host/params/default.json).
r=$(sed -n 's/.*"c_right_deg": *\([-0-9.eE+]*\).*/\1/p' "$work/cal.json")
l=$(sed -n 's/.*"c_left_deg": *\([-0-9.eE+]*\).*/\1/p' "$work/cal.json")
echo "fitted c_r $r°, c_l $l° (plant 1.1001°, -0.8995°)"
check "fitted offsets within 0.1° of the plant's" \
  awk -v r="$r" -v l="$l" 'BEGIN { exit !(r != "" && l != "" && (r - 1.1001)^2 < 0.01 && (l + 0.8995)^2 < 0.01) }'
check "mjc cal show reads the saved calibration" "$mjc" cal show "$work/cal.json"
check "mjc cal upload calibrates node 2 with node 1's file" \
  "$mjc" cal upload "$work/cal.json" --iface vcan0 --node 2
check "mjc cal download reads node 2's calibration back" \
  sh -c "'$mjc' cal download --iface vcan0 --node 2 --out '$work/back.json' && grep -q c_right_deg '$work/back.json'"
check "mjc trial runs the amplitude protocol on node 2" \
  "$mjc" trial --iface vcan0 --node 2 --protocol amplitude --amplitudes 15 --reps 3 \
  --frequency-hz 2 --rest-s 0.2 --out "$work/trial"
check "mjc report re-renders the trial's tables from windows.csv" \
  sh -c "'$mjc' report '$work/trial' --protocol amplitude --reps 3 >'$work/report.out' && grep -q '15°' '$work/report.out' && test -s '$work/trial/report.md'"
check "mjc monitor shows node 2 live" \
  sh -c "'$mjc' monitor --iface vcan0 --node 2 --seconds 1 >'$work/monitor.out' && grep -q 'node 2: idle *calibrated' '$work/monitor.out'"
check "mjc monitor reports an absent node silent, exit 3" \
  sh -c "'$mjc' monitor --iface vcan0 --node 6 --seconds 2.5 >'$work/silent.out'; test \$? -eq 3 && grep -q 'node 6: silent' '$work/silent.out'"
check "every window of the trial reached the host (3 flexions, 3 extensions)" \
  sh -c "test \$(grep -c ',flexion,' '$work/trial/windows.csv') -eq 3 && test \$(grep -c ',extension,' '$work/trial/windows.csv') -eq 3"

wait "$logger"
check "mjc log wrote candump lines" grep -qE '^\([0-9]+\.[0-9]{6}\) vcan0 [0-9A-F]{3}#' "$work/bus.log"
check "can-utils log2asc reads mjc's log" sh -c "log2asc -I '$work/bus.log' -O '$work/bus.asc' vcan0 && grep -q ' Rx ' '$work/bus.asc'"

# cansend a stop command (node 1, sequence 0x2A): the board answers on 0x041.
candump -n 1 -T 2000 vcan0,041:7FF >"$work/answer.txt" 2>&1 &
dumper=$!
sleep 0.3
cansend vcan0 021#012A
wait "$dumper"
check "cansend command gets the board's CommandResult in candump" grep -q '041.*01 00 00 2A' "$work/answer.txt"

cat >"$work/bad.json" <<'JSON'
{"c_right_deg": 1.0, "c_left_deg": 2.0, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
check "a calibration with c_l above c_r is refused before the bus" \
  sh -c "! '$mjc' cal upload '$work/bad.json' --iface vcan0 --node 1 2>'$work/bad.err' && grep -q 'c_left above c_right' '$work/bad.err'"
check "an absent node is reported, exit 3" \
  sh -c "'$mjc' cal upload '$work/cal.json' --iface vcan0 --node 5 --timeout-ms 300 2>'$work/absent.err'; test \$? -eq 3 && grep -q 'did not answer' '$work/absent.err'"
check "a missing interface is reported" \
  sh -c "! '$mjc' log --iface nosuch0 --seconds 1 2>'$work/noif.err' && grep -q nosuch0 '$work/noif.err'"
check "a bad flag is reported, exit non-zero" sh -c "! '$mjc' sim --node 9 2>/dev/null"

# A board with flash keeps its calibration over a restart.
"$mjc" sim --iface vcan0 --node 3 --flash "$work/node3.flash" --speed 4 --seconds 30 2>"$work/sim3a.err" &
sim3=$!
sleep 0.5
check "node 3 stores an uploaded calibration" "$mjc" cal upload "$work/cal.json" --iface vcan0 --node 3
kill "$sim3"
wait "$sim3" 2>/dev/null
"$mjc" sim --iface vcan0 --node 3 --flash "$work/node3.flash" --speed 4 --seconds 30 2>"$work/sim3b.err" &
sim3=$!
sleep 0.5
check "restarted node 3 restores it from flash" grep -q 'restored calibration #1' "$work/sim3b.err"
check "and reports it calibrated" \
  sh -c "'$mjc' cal download --iface vcan0 --node 3 >'$work/back3.json' && grep -q c_right_deg '$work/back3.json'"
kill "$sim3"
wait "$sim3" 2>/dev/null

kill "$sim" "$sim2" 2>/dev/null
wait "$sim" "$sim2" 2>/dev/null
check "mjc sim accounted for every frame (no malformed)" grep -q 'malformed 0' "$work/sim.err"

if [ "$failed" -ne 0 ]; then
  echo "--- details"; tail -n 40 "$work/check.log" "$work/sim.err"
fi
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
