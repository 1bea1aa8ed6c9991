#!/bin/bash
# However the host tool ends, the board stops and the files keep what arrived (run
# inside the VM by scripts/kernel-vm). For mjc trial and mjc calibrate, mid-motion:
#   - SIGINT, SIGTERM, SIGHUP, SIGQUIT: exit 6, the board stopped (idle, not faulted),
#     every window (sample) the tool said it received in windows.csv (sweep.csv), and
#     run.json saying "interrupted";
#   - SIGKILL: the board stops by itself (fault 302), windows.csv holds the windows
#     received before the kill (at most the one in flight missing), run.json still says
#     "running" and mjc report reads the folder ("the host stopped after N windows");
#   - stderr into a pipe that closes (`2>&1 | head -n 1`): the run goes on to its end
#     (its progress lost, not its data), exit 0;
#   - stdout into a pipe that closes: the run goes on to its end, then exit 1 (its
#     tables could not be written) with its files whole.
# And mjc monitor --json writes the board's instance as mjc list --json does.
# The windows received are counted from the trial's progress lines (plain lines: its
# stderr is a file), each printed as its window arrives, before it is written.
# Prints host_kill_windows_lost (received before the SIGKILL, missing from the file).
# usage: host_death.sh <path of mjc>
set -u
mjc=$1
work=$(mktemp -d)
. "$(dirname "$0")/checks.sh"
. "$(dirname "$0")/receivers.sh"

# The plant's own slack (sim_host/params/default.json), so no sweep is needed first.
cat >"$work/cal.json" <<'JSON'
{"c_right_deg": 1.1001, "c_left_deg": -0.8995, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
"$mjc" sim --iface vcan0 --node 1 2>"$work/sim.err" &
sim=$!
check "the simulated board comes up" wait_for "$work/sim.err" "mjc sim: node 1 on vcan0"
check "calibration upload" "$mjc" cal upload "$work/cal.json" --iface vcan0 --node 1

# One representation of the board's instance: mjc monitor --json writes it as mjc list
# --json does (four hex digits).
"$mjc" list --iface vcan0 --json >"$work/list.json" 2>"$work/list.err"
"$mjc" monitor --iface vcan0 --node 1 --json >"$work/monitor.json" 2>"$work/monitor.err" &
monitor=$!
check "mjc monitor --json names the board's instance" \
  wait_for "$work/monitor.json" '"instance":'
kill -INT "$monitor"
wait "$monitor"
check "  as mjc list --json does" test "$(jq -r 'select(.instance) | .instance' \
  "$work/monitor.json" | head -n 1)" = "$(jq -r .instance "$work/list.json")"

# The board's heartbeats (0x301: state, flags) and its Fault frames (0x011).
count_receivers
base=$receivers
stdbuf -oL candump -L vcan0,301:7FF vcan0,011:7FF >"$work/bus.log" 2>&1 &
dumper=$!
wait_receivers $((base + 1))

now() { date +%s.%N; }
first_after() {  # T ID DATA: the timestamp of the first such frame logged after T
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
no_fault_after() {  # T: no Fault frame logged after T
  ! awk -v t="$1" '{ gsub(/[()]/, "", $1) } $1 > t' "$work/bus.log" | grep -q ' 011#'
}
rows() { echo $(($(wc -l <"$1") - 2)); }  # a CSV's rows below its note and header
received() { grep -cE 'repetition [0-9]+/20 (flexion|extension)$' "$1"; }
outcome() { jq -r .end.outcome "$1/run.json"; }

start_trial() {  # NAME: a 40 s trial in the background, once two windows are in
  "$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 20 \
    --frequency-hz 0.5 --rest-s 0.2 --no-figure --out "$work/$1" \
    >"$work/$1.out" 2>"$work/$1.err" &
  pid=$!
  wait_for "$work/$1.err" "repetition 2/20 flexion" "$pid"
}
start_sweep() {  # NAME: a 80 s sweep in the background, once its second cycle runs
  "$mjc" calibrate --iface vcan0 --node 1 --cycles 40 --frequency-hz 0.5 --no-upload \
    --out "$work/$1" >"$work/$1.out" 2>"$work/$1.err" &
  pid=$!
  wait_for "$work/$1.err" "[sweep] cycle 2/40" "$pid"
}

for sig in INT TERM HUP QUIT; do
  name=trial_$sig
  check "a trial runs ($name)" start_trial "$name"
  t0=$(now)
  kill "-$sig" "$pid"
  wait "$pid"
  check_exit $? 6 "mjc trial exits 6 on SIG$sig"
  check "  the board says idle, bridge off" wait_after "$t0" 301 0001
  check "  and it was not a fault" no_fault_after "$t0"
  n=$(received "$work/$name.err")
  check "  every window received ($n) in windows.csv" \
    test "$(rows "$work/$name/windows.csv")" = "$n"
  check "  and said: '$n windows saved'" grep -q "stopped; $n windows saved to" \
    "$work/$name.err"
  check "  run.json: interrupted" test "$(outcome "$work/$name")" = interrupted

  name=sweep_$sig
  check "a calibration sweep runs ($name)" start_sweep "$name"
  t0=$(now)
  kill "-$sig" "$pid"
  wait "$pid"
  check_exit $? 6 "mjc calibrate exits 6 on SIG$sig"
  check "  the board says idle, bridge off" wait_after "$t0" 301 0001
  check "  and it was not a fault" no_fault_after "$t0"
  n=$(sed -n 's/.*stopped; \([0-9]*\) sweep samples saved.*/\1/p' "$work/$name.err")
  check "  every sample it took (${n:-?}) in sweep.csv" \
    test "$(rows "$work/$name/sweep.csv")" = "${n:-x}"
  check "  run.json: interrupted" test "$(outcome "$work/$name")" = interrupted
done

# SIGKILL: nothing of the tool's runs after it; the board and the files must do.
check "a trial runs (trial_KILL)" start_trial trial_KILL
t0=$(now)
kill -KILL "$pid"
wait "$pid" 2>/dev/null
check "the board stops the orphaned trial: fault 302" wait_after "$t0" 011 2E01
n=$(received "$work/trial_KILL.err")
kept=$(rows "$work/trial_KILL/windows.csv")
lost=$((n - kept))
echo "host_kill_windows_lost: $lost windows (of $n received before mjc trial's SIGKILL, missing from windows.csv; goal <= 1)"
check "  windows.csv holds the $n windows received, but at most the one in flight ($kept)" \
  test "$lost" -ge 0 -a "$lost" -le 1
check "  run.json still says running" test "$(outcome "$work/trial_KILL")" = running
"$mjc" report --no-figure "$work/trial_KILL" >"$work/report.out" 2>"$work/report.err"
check_exit $? 0 "  mjc report reads the folder"
check "  saying the host stopped after $kept windows" \
  grep -q "the host stopped after $kept windows without a word" "$work/report.err"
check "  mjc clear releases the fault" "$mjc" clear --iface vcan0 --node 1

check "a calibration sweep runs (sweep_KILL)" start_sweep sweep_KILL
t0=$(now)
kill -KILL "$pid"
wait "$pid" 2>/dev/null
check "the board stops the orphaned sweep: fault 302" wait_after "$t0" 011 2E01
check "  sweep.csv holds the samples of its first cycle at least (2 s at 1 kHz)" \
  test "$(rows "$work/sweep_KILL/sweep.csv")" -ge 1000
check "  its last line whole" \
  test "$(tail -c 1 "$work/sweep_KILL/sweep.csv" | od -An -tx1 | tr -d ' ')" = 0a
check "  run.json still says running" test "$(outcome "$work/sweep_KILL")" = running
check "  mjc clear releases the fault" "$mjc" clear --iface vcan0 --node 1

# A closed stderr: the progress is lost, the run is not.
"$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 3 \
  --frequency-hz 1 --rest-s 0.2 --no-figure --out "$work/pipe_err" \
  2>&1 >"$work/pipe_err.out" | head -n 1 >/dev/null
check_exit "${PIPESTATUS[0]}" 0 "mjc trial with its stderr closed runs to its end"
check "  all 6 windows in windows.csv" test "$(rows "$work/pipe_err/windows.csv")" = 6
check "  run.json: completed" test "$(outcome "$work/pipe_err")" = completed

# A closed stdout: the run ends, its files whole; the tables could not be written.
"$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 3 \
  --frequency-hz 1 --rest-s 0.2 --no-figure --out "$work/pipe_out" \
  2>"$work/pipe_out.err" | true
check_exit "${PIPESTATUS[0]}" 1 "mjc trial with its stdout closed ends with 1"
check "  saying so in one line" grep -q "^mjc trial: error writing stdout" \
  "$work/pipe_out.err"
check "  all 6 windows in windows.csv" test "$(rows "$work/pipe_out/windows.csv")" = 6
check "  run.json: completed" test "$(outcome "$work/pipe_out")" = completed

"$mjc" calibrate --iface vcan0 --node 1 --frequency-hz 1.5 --cycles 6 --no-upload \
  --out "$work/sweep_pipe" 2>&1 >"$work/sweep_pipe.out" | head -n 1 >/dev/null
check_exit "${PIPESTATUS[0]}" 0 "mjc calibrate with its stderr closed runs to its end"
check "  its fit saved" test -s "$work/sweep_pipe/calibration.json"

kill -INT "$sim"
wait "$sim"
kill "$dumper" 2>/dev/null
wait "$dumper" 2>/dev/null
finish "$work/sim.err" "$work"/*.err "$work/bus.log"
