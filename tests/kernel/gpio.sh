#!/bin/bash
# mjc's GPIO lines against the kernel's GPIO character device (run inside the VM by
# scripts/kernel-vm with --module tests/kernel/gpio_chip: the test chip "mjc-test-gpio",
# lines estop 0, sync 1, nrst1 2, nrst2 3, spare4..7, each with a debugfs "input" the
# script drives and counters of the edges the chip's outputs made):
#   - a missing chip, a missing line (by offset and by name), a malformed CHIP:LINE, a
#     line held by another program: one line naming it, exit 1 (2 for the command line);
#   - mjc estop (its line from the config file) with two simulated boards on vcan0, one
#     mid-trial: the press puts one StopAll (0x000 "STOP…") on the bus, both boards
#     report fault 305, the trial ends faulted; held, the stop is repeated, so a board
#     cleared meanwhile is stopped again; released, the boards clear;
#   - an active-low line already active when mjc estop starts: stopped at once;
#   - mjc trial --estop-line: the press ends the trial with exit 6, every board stopped,
#     run.json says emergency_stop; mjc calibrate likewise; mjc monitor shows its line's
#     press and goes on;
#   - mjc trial --sync-line: a rising edge at each flexion window's start and a falling
#     one at each extension's (counted by the chip against windows.csv), low at the end;
#   - mjc reset: the NRST line pulled low for at least 10 ms (the chip's own clock) and
#     released, by --line and from the config file's reset_lines; refused while held;
#   - mjc flash --reset-line: a board that hangs (its mjc sim stopped with SIGSTOP,
#     resumed once the pulse is over: the real chip would be reset at once) restarts on
#     its NRST (mjc sim --reset-line, an input of the test chip wired to the host's
#     output) and the BootHolds catch its bootloader: updated; a board in a motion is
#     refused and its NRST left alone.
# Prints estop_to_stop_frame_ms (estop_latency).
# usage: gpio.sh <path of mjc> <path of estop_latency> <path of mjc-image>
set -u
mjc=$1
latency=$2
packer=$3
work=$(mktemp -d)
. "$(dirname "$0")/checks.sh"
. "$(dirname "$0")/receivers.sh"
chip=mjc-test-gpio
dbg=/sys/kernel/debug/$chip

# "consumer" as gpioinfo shows it on LINE (an offset) of the test chip, or "unused".
holder() { gpioinfo "$chip" | awk -v l="$1" '$1 == "line" && $2 == l":" { print $4; exit }'; }
wait_holder() {  # LINE TEXT: until gpioinfo shows TEXT as LINE's consumer
  local end=$((SECONDS + ${MJC_WAIT_CAP_S:-300}))
  while ((SECONDS < end)); do
    [[ $(holder "$1") == "$2" ]] && return 0
    sleep 0.05
  done
  echo "line $1 is held by $(holder "$1"), not $2"
  return 1
}
# FILE TEXT: FILE holds exactly one line, and it contains TEXT (a one-line error).
one_line() { [[ $(wc -l <"$1") -eq 1 ]] && grep -qF -- "$2" "$1"; }
# Frames of ID (3 hex digits) with data starting DATA logged in the bus log.
frames() { grep -c " $1#$2" "$work/bus.log"; }
wait_frames() {  # ID DATA COUNT: until COUNT such frames are logged
  local end=$((SECONDS + ${MJC_WAIT_CAP_S:-300}))
  while ((SECONDS < end)); do
    (($(frames "$1" "$2") >= $3)) && return 0
    sleep 0.05
  done
  echo "only $(frames "$1" "$2") frames $1#$2"
  return 1
}
fault_after() {  # T ID FAULT: until a frame ID logged after time T has FAULT in bytes 2-3
  local end=$((SECONDS + ${MJC_WAIT_CAP_S:-300}))
  while ((SECONDS < end)); do
    awk -v t="$1" -v id="$2#" -v f="$3" '{ gsub(/[()]/, "", $1) }
      $1 > t && index($3, id) == 1 && substr($3, length(id) + 5, 4) == f { found = 1; exit }
      END { exit !found }' "$work/bus.log" && return 0
    sleep 0.05
  done
  echo "no $2 frame with fault $3 after $1"
  return 1
}
set_input() { echo "$2" >"$dbg/$1/input"; }  # LINE LEVEL: what the outside applies
read_dbg() { cat "$dbg/$1/$2"; }               # LINE FILE

check "the test GPIO chip is there" sh -c "gpiodetect | grep -q '\[$chip\] (8 lines)'"

# --- errors ---------------------------------------------------------------------------
"$mjc" estop --line nochip:0 >"$work/e1.out" 2>"$work/e1.err"
check "a missing chip: exit 1 ($?)" test $? -eq 1
check "  one line naming it" one_line "$work/e1.err" "mjc estop: no GPIO chip 'nochip' for nochip:0 (gpiodetect lists this machine's chips)"
"$mjc" estop --line "$chip:12" 2>"$work/e2.err"
check "a missing line offset: exit 1 ($?)" test $? -eq 1
check "  one line naming it" one_line "$work/e2.err" "mjc estop: GPIO chip gpiochip"
check "  and the chip's lines" grep -qF "[$chip] has lines 0..7: no line 12 ($chip:12)" "$work/e2.err"
"$mjc" reset --line "$chip:nrst9" 2>"$work/e3.err"
check "a missing line name: exit 1 ($?)" test $? -eq 1
check "  one line naming it" one_line "$work/e3.err" "has no line named 'nrst9' ($chip:nrst9;"
"$mjc" trial --sync-line "$chip" --estop-line none 2>"$work/e4.err"
check "a malformed CHIP:LINE: exit 2 ($?)" test $? -eq 2
check "  one line saying so" one_line "$work/e4.err" "mjc trial: --sync-line: '$chip' is not CHIP:LINE: no ':'"

# --- two boards -----------------------------------------------------------------------
cat >"$work/cal.json" <<'JSON'
{"c_right_deg": 1.1001, "c_left_deg": -0.8995, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
"$mjc" sim --iface vcan0 --node 1 --subject subject1 2>"$work/sim1.err" &
sim1=$!
"$mjc" sim --iface vcan0 --node 2 2>"$work/sim2.err" &
sim2=$!
check "two simulated boards come up" wait_for "$work/sim1.err" "mjc sim: node 1 on vcan0"
check "  (node 2)" wait_for "$work/sim2.err" "mjc sim: node 2 on vcan0"
check "calibration upload (node 1)" "$mjc" cal upload "$work/cal.json" --iface vcan0 --node 1
check "calibration upload (node 2)" "$mjc" cal upload "$work/cal.json" --iface vcan0 --node 2

# StopAll (0x000) and both boards' Fault frames (0x011, 0x012), with their timestamps.
count_receivers
base=$receivers
stdbuf -oL candump -L vcan0,000:7FF vcan0,011:7FF vcan0,012:7FF vcan0,301:7FF \
  >"$work/bus.log" 2>&1 &
dumper=$!
wait_receivers $((base + 1))

# --- mjc estop, its line from the config file -----------------------------------------
echo '{"estop_line": "mjc-test-gpio:estop", "reset_lines": {"2": "mjc-test-gpio:3"}}' \
  >"$work/config.json"
export MJC_CONFIG=$work/config.json
"$mjc" estop --iface vcan0 >"$work/estop.out" 2>"$work/estop.err" &
estop=$!
check "mjc estop holds the line named in the config file" wait_holder 0 '"mjc'
check "  and says what it watches" wait_for "$work/estop.err" "watching $chip:estop (active high) for vcan0"
"$mjc" estop --line "$chip:0" 2>"$work/busy.err"
check "a second watch on it: exit 1 ($?)" test $? -eq 1
check "  one line naming the holder" one_line "$work/busy.err" "mjc estop: $chip:0 is busy: held by 'mjc estop' (gpioinfo gpiochip"

"$mjc" trial --iface vcan0 --node 1 --estop-line none --protocol amplitude --amplitudes 15 \
  --reps 20 --frequency-hz 0.5 --rest-s 0.2 --out "$work/t1" >"$work/t1.out" 2>"$work/t1.err" &
trial=$!
check "a trial runs on node 1" wait_for "$work/t1.err" "repetition 1/20"
set_input 0 1  # the press
check "the press: one StopAll on the bus, 'STOP' and mjc estop's session" wait_frames 000 53544F50 1
check "  node 1 reports fault 305" wait_frames 011 3101 1
check "  node 2, at rest, too" wait_frames 012 3101 1
check "  mjc estop says so" wait_for "$work/estop.out" "emergency stop: $chip:estop active: StopAll sent on vcan0"
check "  and names both boards' confirmations" wait_for "$work/estop.out" "node 2 stopped: fault 305 (emergency stop)"
check "  (node 1)" grep -q "node 1 stopped: fault 305 (emergency stop)" "$work/estop.out"
wait "$trial"
check_exit $? 5 "the trial ends faulted"
check "  naming the emergency stop" grep -q "the board faulted: fault 305 (emergency stop)" "$work/t1.err"
check "held, the StopAll is repeated" wait_frames 000 53544F50 3
# A clear while the button is held: the board may take it (then the next repeat stops
# it again) or refuse it (a repeat came first); either way it is stopped after it.
"$mjc" clear --iface vcan0 --node 1 >"$work/clear1.out" 2>&1
t0=$(date +%s.%N)
check "a clear while it is held is judged on fault 305" grep -q "node 1: fault 305 (emergency stop)" "$work/clear1.out"
check "  and node 1's heartbeats after it say fault 305" fault_after "$t0" 301 3101
set_input 0 0  # released
check "released: mjc estop says so" wait_for "$work/estop.out" "$chip:estop released"
check "both boards clear once it is released" "$mjc" clear --iface vcan0 --node 1 --node 2
kill -INT "$estop"
wait "$estop"
check "mjc estop ends on SIGINT with exit 0 ($?)" test $? -eq 0
sent=$(sed -n 's/^mjc estop: 1 emergency stops, \([0-9]*\) StopAll frames sent$/\1/p' "$work/estop.err")
check "  counting what it did: one press, ${sent:-?} StopAll frames" test -n "$sent"
stop_frames_are() { wait_frames 000 53544F50 "$1" && test "$(frames 000 53544F50)" -eq "$1"; }
check "  every one of them on the bus, none more" stop_frames_are "${sent:-0}"
check "  and lets the line go" wait_holder 0 unused

# An active-low button already pressed (its line low) when the watch starts.
set_input 4 0
"$mjc" estop --iface vcan0 --line "$chip:spare4" --estop-active low >"$work/low.out" 2>&1 &
low=$!
check "an active-low line active at the start stops every board at once" wait_for "$work/low.out" "$chip:spare4 active at the start: StopAll sent on vcan0"
set_input 4 1
check "  released when it goes high" wait_for "$work/low.out" "$chip:spare4 released"
kill -INT "$low"
wait "$low"
check "both boards clear" "$mjc" clear --iface vcan0 --node 1 --node 2

# --- mjc trial --estop-line -----------------------------------------------------------
"$mjc" trial --iface vcan0 --node 1 --estop-line "$chip:estop" --protocol amplitude \
  --amplitudes 15 --reps 20 --frequency-hz 0.5 --rest-s 0.2 --out "$work/t2" \
  >"$work/t2.out" 2>"$work/t2.err" &
trial=$!
check "a trial watching the line runs" wait_for "$work/t2.err" "repetition 1/20"
check "  holding the line" wait_holder 0 '"mjc'
node2_faults=$(frames 012 3101)
set_input 0 1
wait "$trial"
check_exit $? 6 "the press ends it"
check "  saying every board was told to stop and node 1 confirmed" \
  grep -q "^mjc trial: emergency stop on $chip:estop: every board was told to stop; node 1 stopped (fault 305, emergency stop: mjc clear --node 1 releases it); [0-9]* windows saved to $work/t2/windows.csv" "$work/t2.err"
check "  run.json: emergency_stop" grep -q '"outcome": "emergency_stop"' "$work/t2/run.json"
check "  node 2 was stopped too" wait_frames 012 3101 $((node2_faults + 1))
set_input 0 0
check "both boards clear" "$mjc" clear --iface vcan0 --node 1 --node 2

# --- mjc calibrate and mjc monitor with --estop-line -----------------------------------
"$mjc" monitor --iface vcan0 --node 2 --interval-ms 200 --estop-line "$chip:spare6" \
  >"$work/monitor.out" 2>&1 &
monitor=$!
check "mjc monitor watches a line when given one" wait_holder 6 '"mjc'
mkdir -p "$work/cal"
"$mjc" calibrate --iface vcan0 --node 1 --cycles 40 --frequency-hz 0.5 \
  --estop-line "$chip:estop" --out "$work/cal" >"$work/cal.out" 2>"$work/cal.err" &
sweep=$!
check "a calibration sweep watching the line runs" wait_for "$work/cal.err" "[sweep] cycle"
set_input 0 1
wait "$sweep"
check_exit $? 6 "the press ends it"
check "  saying so, with the samples kept and nothing fitted" \
  grep -q "^mjc calibrate: emergency stop on $chip:estop: every board was told to stop; node 1 stopped (fault 305, emergency stop: mjc clear --node 1 releases it); [0-9]* sweep samples saved to $work/cal/sweep.csv (not fitted)" "$work/cal.err"
check "  run.json: emergency_stop" grep -q '"outcome": "emergency_stop"' "$work/cal/run.json"
set_input 0 0
set_input 6 1
check "the monitor shows a press of its line" wait_for "$work/monitor.out" "emergency stop on $chip:spare6: every board was told to stop"
check "  and goes on" kill -0 "$monitor"
set_input 6 0
kill -INT "$monitor"
wait "$monitor"
check "both boards clear" "$mjc" clear --iface vcan0 --node 1 --node 2

# --- mjc trial --sync-line ------------------------------------------------------------
rising0=$(read_dbg 1 rising)
falling0=$(read_dbg 1 falling)
"$mjc" trial --iface vcan0 --node 1 --sync-line "$chip:sync" --protocol amplitude \
  --amplitudes 10 15 --reps 3 --frequency-hz 1 --rest-s 0.2 --out "$work/t3" --no-figure \
  >"$work/t3.out" 2>"$work/t3.err"
check_exit $? 0 "a trial with a sync line completes"
flexions=$(grep -c ',flexion,' "$work/t3/windows.csv")
extensions=$(grep -c ',extension,' "$work/t3/windows.csv")
rising=$(($(read_dbg 1 rising) - rising0))
falling=$(($(read_dbg 1 falling) - falling0))
check "a rising edge at each flexion window ($rising edges, $flexions windows)" test "$rising" -eq "$flexions" -a "$flexions" -eq 6
check "a falling edge at each extension window ($falling edges, $extensions windows)" test "$falling" -eq "$extensions" -a "$extensions" -eq 6
check "  low at the end" test "$(read_dbg 1 level)" -eq 0
check "  mjc trial counts them" grep -q "^sync: $chip:sync: 12 window starts, 12 edges" "$work/t3.out"

# --- mjc reset ------------------------------------------------------------------------
set_input 2 1  # the board's pull-up on NRST
set_input 3 1
"$mjc" reset --node 1 --line "$chip:nrst1" >"$work/r1.out" 2>&1
check "mjc reset --line ($?)" test $? -eq 0
check "  NRST went low once and came back" test "$(read_dbg 2 falling) $(read_dbg 2 rising) $(read_dbg 2 level)" = "1 2 1"
low_ns=$(read_dbg 2 last_low_ns)
check "  held low at least 10 ms by the chip's clock ($low_ns ns)" test "$low_ns" -ge 10000000
check "  and let go" wait_holder 2 unused
"$mjc" reset --node 2 >"$work/r2.out" 2>&1
check "mjc reset --node 2 takes its line from the config file ($?)" test $? -eq 0
check "  line 3 pulsed" test "$(read_dbg 3 falling) $(read_dbg 3 last_low_ns)" != "0 0"
check "  saying which" grep -q "node 2 reset: $chip:3 held low 10 ms, then released" "$work/r2.out"
gpioset --mode=signal "$chip" 2=1 &
holder_pid=$!
wait_holder 2 '"gpioset"' >/dev/null
"$mjc" reset --line "$chip:nrst1" 2>"$work/r3.err"
check "a reset line held by another program: exit 1 ($?)" test $? -eq 1
check "  one line naming the holder" one_line "$work/r3.err" "mjc reset: $chip:nrst1 is busy: held by 'gpioset'"
kill "$holder_pid"
wait "$holder_pid" 2>/dev/null
unset MJC_CONFIG

# --- mjc flash --reset-line ---------------------------------------------------------
# Board 3's NRST pin is line 7, wired to the host's nrst2 output (line 3); its pull-up
# keeps it high.
new=5eed1234
{
  printf '\x00\x80\x01\x20\x01\x44\x00\x08'
  yes "maestro-jc test image $new" | head -c $((8192 - 8))
} >"$work/app.raw"
check "an image packs" "$packer" pack "$work/app.raw" "$work/new.bin" --hardware 1 1 \
  --load-address 0x08004200 --commit $new --dirty 0 --commit-time 1795486377 \
  --describe "test-$new" --board-type 1
set_input 3 1
echo 3 >"$dbg/7/follow"
"$mjc" sim --iface vcan0 --node 3 --reset-line "$chip:spare7" 2>"$work/sim3.err" &
sim3=$!
check "board 3 comes up, its NRST on a GPIO line" wait_for "$work/sim3.err" "mjc sim: node 3 on vcan0"
check "  holding it" wait_holder 7 '"mjc'
kill -STOP "$sim3"  # it hangs: no frame, no answer
falling3=$(read_dbg 3 falling)
"$mjc" flash --iface vcan0 --node 3 --reset-line "$chip:nrst2" "$work/new.bin" \
  >"$work/flash.out" 2>"$work/flash.err" &
flash=$!
check "mjc flash pulses its reset line after the first hold" wait_for "$work/flash.err" "mjc flash: node 3: $chip:nrst2 pulsed low 10 ms"
kill -CONT "$sim3"
wait "$flash"
check_exit $? 0 "the hanging board is updated"
check "  saying so" grep -q "^node 3: updated to $new" "$work/flash.out"
check "  it restarted on its pin" grep -q "mjc sim: reset (reset pin)" "$work/sim3.err"
check "  and its bootloader was held by the host" grep -q "node 3: bootloader stays: ready (held by a host)" "$work/sim3.err"
check "  (its application never took a hold)" sh -c "! grep -q 'entering the bootloader' '$work/sim3.err'"
check "  one pulse on the wire" test "$(read_dbg 3 falling)" -eq $((falling3 + 1))
kill -INT "$sim3"
wait "$sim3"
# A board in a motion is not reset under a person's hand.
"$mjc" trial --iface vcan0 --node 1 --estop-line none --protocol amplitude --amplitudes 15 \
  --reps 20 --frequency-hz 0.5 --rest-s 0.2 --out "$work/t4" >"$work/t4.out" 2>"$work/t4.err" &
trial=$!
check "a trial runs on node 1" wait_for "$work/t4.err" "repetition 1/20"
falling2=$(read_dbg 2 falling)
"$mjc" flash --iface vcan0 --node 1 --reset-line "$chip:nrst1" "$work/new.bin" \
  >/dev/null 2>"$work/flash1.err"
check_exit $? 4 "mjc flash --reset-line refuses a board in a motion"
check "  saying why" grep -q "node 1 is running a motion: stop it first (mjc stop --node 1); nothing was done (its reset line would stop it mid-motion)" "$work/flash1.err"
check "  and its NRST was not touched" test "$(read_dbg 2 falling)" -eq "$falling2"
"$mjc" stop --iface vcan0 --node 1 >/dev/null 2>&1
wait "$trial"

# --- the figure -----------------------------------------------------------------------
"$mjc" estop --iface vcan0 --line "$chip:spare5" >"$work/bench.out" 2>&1 &
estop=$!
wait_holder 5 '"mjc' >/dev/null
"$latency" "$dbg/5/input" vcan0 20 >"$work/latency.out" 2>&1
check "estop_latency measured 20 presses" grep -q "^estop_to_stop_frame_ms: " "$work/latency.out"
grep "^estop_to_stop_frame_ms: " "$work/latency.out"
kill -INT "$estop"
wait "$estop"

kill -INT "$sim1" "$sim2"
wait "$sim1" "$sim2"
kill "$dumper" 2>/dev/null
wait "$dumper" 2>/dev/null
finish "$work/estop.out" "$work/estop.err" "$work/t1.err" "$work/t2.err" "$work/t3.err" \
  "$work/t3.out" "$work/flash.err" "$work/sim3.err" "$work/bus.log" "$work/latency.out"
