#!/bin/bash
# Interrupting is safe (run inside the VM by scripts/kernel-vm): a person's finger is in
# the device, so a tool that started a motion stops it when it is interrupted, and a
# motion whose commander died stops although another tool's heartbeats are on the bus.
#   - SIGINT to mjc trial mid-trial, with mjc monitor running beside it: exit 6, the
#     board stopped (confirmed) and idle, not faulted, every window that arrived saved;
#   - SIGTERM to mjc calibrate mid-sweep: exit 6, the board stopped, the samples saved;
#   - mjc stop from another terminal: the trial exits 6 saying it was stopped;
#   - mjc trial killed (SIGKILL) with mjc monitor running: the board stops the orphaned
#     motion (fault 302) although the monitor's heartbeats go on; the next trial is
#     refused naming fault 302 and mjc clear.
# Prints interrupt_to_stop_ms (the signal to the board's heartbeat saying its bridge is
# off) and orphan_motion_s (the kill to the board's Fault frame).
# usage: interrupt.sh <path of mjc>
set -u
mjc=$1
work=$(mktemp -d)
. "$(dirname "$0")/checks.sh"
. "$(dirname "$0")/receivers.sh"

# The plant's own slack (sim_host/params/default.json), so no sweep is needed.
cat >"$work/cal.json" <<'JSON'
{"c_right_deg": 1.1001, "c_left_deg": -0.8995, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
"$mjc" sim --iface vcan0 --node 1 --subject subject1 2>"$work/sim.err" &
sim=$!
check "the simulated board comes up" wait_for "$work/sim.err" "mjc sim: node 1 on vcan0"
check "calibration upload" "$mjc" cal upload "$work/cal.json" --iface vcan0 --node 1

# The board's heartbeats (0x301: state, flags with bridge_enabled in bit 1) and its
# Fault frames (0x011), with the kernel's timestamps.
count_receivers
base=$receivers
stdbuf -oL candump -L vcan0,301:7FF vcan0,011:7FF >"$work/bus.log" 2>&1 &
dumper=$!
"$mjc" monitor --iface vcan0 --node 1 --interval-ms 200 >"$work/monitor.out" 2>&1 &
monitor=$!
wait_receivers $((base + 2))

now() { date +%s.%N; }
# The first frame of ID (with DATA's leading bytes) logged after time T: its timestamp.
first_after() {  # T ID DATA
  awk -v t="$1" -v want="$2#$3" '{ gsub(/[()]/, "", $1) }
    $1 > t && index($3, want) == 1 { print $1; exit }' "$work/bus.log"
}
wait_after() {  # T ID DATA: waits until such a frame is logged after T (cap as wait_for)
  local end=$((SECONDS + ${MJC_WAIT_CAP_S:-300}))
  while ((SECONDS < end)); do
    [ -n "$(first_after "$@")" ] && return 0
    sleep 0.05
  done
  return 1
}
start_trial() {  # OUT: a 40 s trial in the background, once its first window is in
  "$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 20 \
    --frequency-hz 0.5 --rest-s 0.2 --out "$work/$1" >"$work/$1.out" 2>"$work/$1.err" &
  trial=$!
  wait_for "$work/$1.err" "repetition 1/20" "$trial"
}

# SIGNAL PID TOOL WHAT CSV ERR [TAIL]: interrupts TOOL (mjc trial, mjc calibrate),
# running as PID, with SIGNAL; checks that it exits 6 saying on ERR that it stopped the
# board and saved N of WHAT to CSV (then TAIL), and that CSV holds those N rows below
# its two header lines.
interrupt_keeps() {
  local signal=$1 pid=$2 tool=$3 what=$4 csv=$5 err=$6 tail=${7:-} n
  kill "-$signal" "$pid"
  wait "$pid"
  check_exit $? 6 "$tool exits 6 on SIG$signal"
  check "  saying it stopped the board and where the $what are" \
    grep -q "^$tool: interrupted: node 1 stopped; [1-9][0-9]* $what saved to $csv$tail" "$err"
  n=$(sed -n "s/.*stopped; \([0-9]*\) $what saved.*/\1/p" "$err")
  check "  every one of them in ${csv##*/} (${n:-?})" \
    test "$(($(wc -l <"$csv") - 2))" = "${n:-x}"
}

# SIGINT mid-trial, a monitor beside it.
check "a trial runs, mjc monitor beside it" start_trial int
t0=$(now)
interrupt_keeps INT "$trial" "mjc trial" windows "$work/int/windows.csv" "$work/int.err"
check "the board says idle, bridge off, calibrated" wait_after "$t0" 301 0001
t1=$(first_after "$t0" 301 0001)
check "  and it was not a fault" sh -c "! awk -v t=$t0 '{ gsub(/[()]/, \"\", \$1) } \$1 > t' '$work/bus.log' | grep -q ' 011#'"
stop_ms=$(awk -v a="$t0" -v b="${t1:-0}" 'BEGIN { printf "%.1f", (b - a) * 1000 }')
echo "interrupt_to_stop_ms: $stop_ms ms (SIGINT to mjc trial, to the board's heartbeat with its bridge off)"

# SIGTERM mid-sweep.
mkdir -p "$work/cal"
t0=$(now)
"$mjc" calibrate --iface vcan0 --node 1 --cycles 40 --frequency-hz 0.5 \
  --out "$work/cal" >"$work/sweep.out" 2>"$work/sweep.err" &
sweep=$!
check "a calibration sweep runs" wait_after "$t0" 301 0103  # calibrating, bridge on
# Samples in hand first: a board slowed by a loaded machine can be calibrating for
# seconds of wall time before its first angle telemetry reaches the tool.
check "  its second cycle under way" wait_for "$work/sweep.err" "[sweep] cycle 2/40" "$sweep"
interrupt_keeps TERM "$sweep" "mjc calibrate" "sweep samples" "$work/cal/sweep.csv" \
  "$work/sweep.err" " (not fitted)"
check "  and no calibration written" test ! -e "$work/cal/calibration.json"

# mjc stop from another terminal.
check "another trial runs" start_trial stopped
"$mjc" stop --iface vcan0 --node 1 >"$work/stop.out" 2>&1
wait "$trial"
check_exit $? 6 "a trial stopped by mjc stop exits 6"
check "  saying it was stopped before its end" grep -q "stopped before its end" "$work/stopped.err"

# The commander dies; the monitor's heartbeats go on.
check "a third trial runs" start_trial orphan
t0=$(now)
kill -KILL "$trial"
wait "$trial" 2>/dev/null
check "the board stops the orphaned trial: fault 302" wait_after "$t0" 011 2E01
t1=$(first_after "$t0" 011 2E01)
awk -v a="$t0" -v b="${t1:-0}" 'BEGIN { printf "orphan_motion_s: %.3f s (commander killed, another session heartbeating, to the Fault frame; the board waits its host timeout, 0.3 s)\n", b - a }'
check "  the monitor was sending all along" kill -0 "$monitor"
"$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 3 \
  --out "$work/refused" >"$work/refused.out" 2>"$work/refused.err"
check_exit $? 4 "the next trial is refused, exit 4"
check "  naming the fault and mjc clear" \
  grep -q "holds fault 302 (host heartbeat lost).*mjc clear --node 1" "$work/refused.err"

kill -INT "$monitor" "$sim"
wait "$monitor" "$sim"
kill "$dumper" 2>/dev/null
wait "$dumper" 2>/dev/null
finish "$work/sim.err" "$work/int.err" "$work/sweep.err" "$work/stopped.err" \
  "$work/refused.err" "$work/bus.log"
