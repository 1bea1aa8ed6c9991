#!/bin/bash
# mjc end to end on Debian's CAN stack (run inside the VM by scripts/kernel-vm): a
# simulated board (`mjc sim`, or the board MJC_BOARD names: board.sh) on vcan0, `mjc log`
# recording, `mjc calibrate` running the sweep, the fit and the ISO-TP upload over the
# bus; can-utils reading our log and talking to the board; refusals with reasons, one
# line each, and their exit statuses (host_tools/mjc/commands.h: Exit).
# usage: [MJC_BOARD=<board command>] mjc_end_to_end.sh <path of mjc>
set -u
mjc=$1
work=$(mktemp -d)
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
plant=$here/../../sim_host/params/default.json
. "$(dirname "$0")/checks.sh"

# Readiness: a listener started in the background is ready once the CAN core has
# registered its receiver on vcan0.
. "$(dirname "$0")/receivers.sh"
# The board under test and wait_board (board.sh).
. "$(dirname "$0")/board.sh"
# One line on stderr and exit status STATUS: the refusal contract.
refuses() {  # STATUS ERRFILE COMMAND...: COMMAND exits STATUS with one stderr line
  local want=$1 err=$2 got
  shift 2
  "$@" 2>"$err"
  got=$?
  echo "exit $got (want $want): $(cat "$err")"
  [ "$got" -eq "$want" ] && [ "$(wc -l <"$err")" -eq 1 ]
}

# A number from a JSON file with its key once in it (python3's start-up costs seconds
# under emulation).
json_number() {  # FILE KEY
  sed -n "s/.*\"$2\": *\([-+0-9.eE]*\).*/\1/p" "$1" | head -n 1
}

# The boards keep real time (--speed 1): every wait of the tools and of this script
# follows the boards' own progress, so a machine too slow to keep it only takes longer.
# Node 1, the robot alone, for the calibration; then node 2, a subject's hand donned,
# for the rest (one board at a time: mjc sim takes a fifth of a vCPU, the virtual board
# more).
"${board[@]}" --iface vcan0 --node 1 2>"$work/sim.err" &
sim=$!
check "board 1 comes up" wait_board "$work/sim.err" 1
# can-utils' own recording (one receiver), for mjc log --from to read; then mjc log
# (two: data and error frames), each counted once the ones before are in.
count_receivers
base=$receivers
candump -L vcan0 >"$work/candump.log" 2>"$work/candump.err" &
dumplog=$!
check "candump listens" wait_receivers $((base + 1))
count_receivers
base=$receivers
# It records until stopped after the calibration (not for a wall-clock time, which a
# slow machine could spend before the sweep's angle telemetry starts).
"$mjc" log --iface vcan0 --out "$work/bus.log" 2>"$work/log.err" &
logger=$!
check "mjc log listens" wait_receivers $((base + 2))

# Node 1 first holds a calibration with a distinctive SEA stiffness: calibrate must keep
# it (it replaces only the backlash), not reset it to a default.
cat >"$work/held.json" <<'JSON'
{"c_right_deg": 1.1, "c_left_deg": -0.9, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.65, "joint_zero_count": 0}
JSON
check "node 1 takes a calibration with stiffness 0.65" \
  "$mjc" cal upload "$work/held.json" --iface vcan0 --node 1
# 1.5 Hz: at 2 Hz the 30° sweep moves the bare joint at up to 5.2 rad/s, past the
# board's 5 rad/s velocity limit (fault 203).
check "mjc calibrate: sweep, fit, upload over the bus" \
  "$mjc" calibrate --iface vcan0 --node 1 --frequency-hz 1.5 --cycles 6 --out "$work/cal"
# The plant's slack, from its parameter file; the fit is held to the product goal of
# 0.05° (the simulated calibration tests hold it to the same).
# (Here-strings, not process substitution: the VM has no /dev/fd.)
want_r=$(awk -v r="$(json_number "$plant" c_right_rad)" 'BEGIN { print r * 45 / atan2(1, 1) }')
want_l=$(awk -v r="$(json_number "$plant" c_left_rad)" 'BEGIN { print r * 45 / atan2(1, 1) }')
r=$(json_number "$work/cal/calibration.json" c_right_deg)
l=$(json_number "$work/cal/calibration.json" c_left_deg)
stiffness=$(json_number "$work/cal/calibration.json" sea_stiffness_Nm_per_rad)
echo "fitted c_r ${r:-?}°, c_l ${l:-?}° (plant ${want_r:-?}°, ${want_l:-?}°)"
kill -INT "$logger"
check "fitted offsets within 0.05° of the plant's" \
  awk -v r="${r:-}" -v l="${l:-}" -v R="${want_r:-}" -v L="${want_l:-}" \
  'BEGIN { exit !(r != "" && R != "" && (r - R)^2 < 0.05^2 && (l - L)^2 < 0.05^2) }'
check "the calibration keeps the stiffness node 1 held" \
  awk -v k="${stiffness:-}" 'BEGIN { exit !(k != "" && (k - 0.65)^2 < 1e-12) }'
check "mjc cal show reads the saved calibration" "$mjc" cal show "$work/cal/calibration.json"
# cansend a stop command (node 1, sequence 0x2A, no session, no configuration: 8
# bytes): the board answers on 0x041, naming the sequence and session it answers.
count_receivers
base=$receivers
candump -n 1 vcan0,041:7FF >"$work/answer.txt" 2>&1 &
dumper=$!
wait_receivers $((base + 1))
cansend vcan0 021#012A000000000000
wait "$dumper"
check "cansend command gets the board's CommandResult in candump" grep -q '041.*01 00 00 2A 00 00 00 00' "$work/answer.txt"
kill "$sim"
wait "$sim"
check "board 1 accounted for every frame (no malformed)" grep -q 'malformed 0' "$work/sim.err"

"${board[@]}" --iface vcan0 --node 2 --subject subject1 2>"$work/sim2.err" &
sim2=$!
check "board 2 comes up" wait_board "$work/sim2.err" 2
check "mjc cal upload calibrates node 2 with node 1's file" \
  "$mjc" cal upload "$work/cal/calibration.json" --iface vcan0 --node 2
check "mjc cal download reads node 2's calibration back" \
  sh -c "'$mjc' cal download --iface vcan0 --node 2 --out '$work/back.json' && grep -q c_right_deg '$work/back.json' && ! grep -q fit_rms_urad '$work/back.json'"
check "mjc trial runs the amplitude protocol on node 2" \
  "$mjc" trial --iface vcan0 --node 2 --protocol amplitude --amplitudes 15 --reps 3 \
  --frequency-hz 2 --rest-s 0.2 --out "$work/trial" --no-figure
check "mjc report re-renders the trial's tables from windows.csv" \
  sh -c "'$mjc' report '$work/trial' --protocol amplitude --no-figure >'$work/report.out' && grep -q '15°' '$work/report.out' && test -s '$work/trial/report.md'"
# The same trial again as trial 2 at 20°: two amplitudes, so the protocol is amplitude.
mkdir -p "$work/two"
{ cat "$work/trial/windows.csv"; tail -n +3 "$work/trial/windows.csv" | sed 's/^1,15,/2,20,/'; } \
  >"$work/two/windows.csv"
check "mjc report derives the amplitude protocol from windows.csv" \
  sh -c "'$mjc' report '$work/two' --no-figure >'$work/two.out' && grep -q '20°' '$work/two.out'"
check "mjc report refuses a protocol its windows.csv contradicts, exit 1" \
  refuses 1 "$work/contra.err" "$mjc" report "$work/two" --protocol repeatability
check "  saying why" grep -q 'differ in amplitude' "$work/contra.err"
"$mjc" monitor --iface vcan0 --node 2 --interval-ms 100 >"$work/monitor.out" 2>&1 &
monitor=$!
check "mjc monitor shows node 2 live" wait_for "$work/monitor.out" "node 2: idle"
check "  calibrated" grep -q 'node 2: idle *calibrated' "$work/monitor.out"
kill -INT "$monitor"
wait "$monitor"
check "mjc monitor reports an absent node silent, exit 3" \
  sh -c "'$mjc' monitor --iface vcan0 --node 6 --seconds 2.5 >'$work/silent.out' 2>'$work/silent.err'; test \$? -eq 3 && grep -q 'node 6: no data yet' '$work/silent.out' && grep -q 'node 6 is silent (is the board powered and on vcan0? try mjc list)' '$work/silent.err'"
check "every window of the trial reached the host (3 flexions, 3 extensions)" \
  sh -c "test \$(grep -c ',flexion,' '$work/trial/windows.csv') -eq 3 && test \$(grep -c ',extension,' '$work/trial/windows.csv') -eq 3"

wait "$logger"
check "mjc log wrote candump lines" grep -qE '^\([0-9]+\.[0-9]{6}\) vcan0 [0-9A-F]{3}#' "$work/bus.log"
check "can-utils log2asc reads mjc's log" sh -c "log2asc -I '$work/bus.log' -O '$work/bus.asc' vcan0 && grep -q ' Rx ' '$work/bus.asc'"
kill -INT "$dumplog"
wait "$dumplog"
check "candump recorded the bus" test -s "$work/candump.log"
check "mjc log --from reads candump's log back line for line" \
  sh -c "'$mjc' log --from '$work/candump.log' >'$work/candump.again' 2>/dev/null && cmp '$work/candump.log' '$work/candump.again'"
lines=$(wc -l <"$work/bus.log")
check "mjc log --from decodes every line of mjc's own log to CSV" \
  sh -c "'$mjc' log --from '$work/bus.log' --format csv --out '$work/bus.csv' 2>'$work/from.err' && grep -q '^mjc log: $lines frames from' '$work/from.err' && grep -q ',TelemetryAngles,motor_angle_rad,' '$work/bus.csv'"
# A damaged copy: line 3 cut short. The other lines are still decoded; the command
# fails (exit 1) naming the first bad line.
{ head -n 2 "$work/bus.log"; head -n 3 "$work/bus.log" | tail -n 1 | cut -c 1-25; tail -n +4 "$work/bus.log"; } \
  >"$work/damaged.log"
"$mjc" log --from "$work/damaged.log" --out "$work/damaged.out" 2>"$work/damaged.err"
status=$?
echo "exit $status: $(cat "$work/damaged.err")"
check "a malformed log line: exit 1, named, the rest decoded" \
  sh -c "test $status -eq 1 && grep -q '1 malformed line(s) skipped.*line 3: ' '$work/damaged.err' && test \$(wc -l <'$work/damaged.out') -eq $((lines - 1))"

cat >"$work/bad.json" <<'JSON'
{"c_right_deg": 1.0, "c_left_deg": 2.0, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
check "a calibration with c_l above c_r is refused before the bus, exit 1" \
  refuses 1 "$work/bad.err" "$mjc" cal upload "$work/bad.json" --iface vcan0 --node 1
check "  saying why" grep -q 'c_left above c_right' "$work/bad.err"
cat >"$work/typed.json" <<'JSON'
{"c_right_deg": 1.0, "c_left_deg": -1.0, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0, "fit_rms_urad": "small"}
JSON
check "a calibration field of the wrong type: one line, exit 1 (not an abort)" \
  refuses 1 "$work/typed.err" "$mjc" cal show "$work/typed.json"
check "  and the line names the command and the field" \
  grep -q "^mjc cal show: .*'fit_rms_urad' must be an integer" "$work/typed.err"
check "a negative fit field is refused, not wrapped" \
  sh -c "sed 's/\"small\"/-5/' '$work/typed.json' >'$work/negative.json' && ! '$mjc' cal show '$work/negative.json' 2>/dev/null"
check "an absent node is reported, exit 3" \
  refuses 3 "$work/absent.err" "$mjc" cal upload "$work/cal/calibration.json" --iface vcan0 --node 5 --timeout-ms 300
check "  in the one wording of an absent node" grep -q 'node 5 is silent (is the board powered and on vcan0? try mjc list)' "$work/absent.err"
check "an unwritable trial folder is refused before the trial runs, exit 1" \
  refuses 1 "$work/noout.err" "$mjc" trial --iface vcan0 --node 2 --out /proc/mjc/trial
mkdir -p "$work/broken"
printf 'not,a,trial\n' >"$work/broken/windows.csv"
check "a windows.csv of another layout is refused, exit 1" \
  refuses 1 "$work/broken.err" "$mjc" report "$work/broken"
check "  saying why" grep -q 'header is not' "$work/broken.err"
check "an unwritable calibration download is refused, exit 1" \
  refuses 1 "$work/download.err" "$mjc" cal download --iface vcan0 --node 2 --out /proc/mjc.json
check "a missing interface is reported, exit 1" \
  refuses 1 "$work/noif.err" "$mjc" log --iface nosuch0 --seconds 1
check "  naming it" grep -q nosuch0 "$work/noif.err"
check "a bad flag is reported, exit 2" refuses 2 "$work/flag.err" "${board[@]}" --node 9

# A board with flash keeps its calibration over a restart.
"${board[@]}" --iface vcan0 --node 3 --flash "$work/node3.flash" 2>"$work/sim3a.err" &
sim3=$!
wait_board "$work/sim3a.err" 3
check "node 3 stores an uploaded calibration" "$mjc" cal upload "$work/cal/calibration.json" --iface vcan0 --node 3
kill "$sim3"
wait "$sim3" 2>/dev/null
"${board[@]}" --iface vcan0 --node 3 --flash "$work/node3.flash" 2>"$work/sim3b.err" &
sim3=$!
wait_board "$work/sim3b.err" 3
check "restarted node 3 restores it from flash" grep -q 'restored calibration #1' "$work/sim3b.err"
check "and reports it calibrated" \
  sh -c "'$mjc' cal download --iface vcan0 --node 3 >'$work/back3.json' && grep -q c_right_deg '$work/back3.json'"
kill "$sim3"
wait "$sim3" 2>/dev/null

kill "$sim2" 2>/dev/null
wait "$sim2" 2>/dev/null
check "board 2 accounted for every frame (no malformed)" grep -q 'malformed 0' "$work/sim2.err"

finish "$work/sim.err" "$work/sim2.err"
