#!/bin/bash
# Faults and their clearing on Debian's CAN stack (run inside the VM by
# scripts/kernel-vm).
#
# CAN bus-off: a CAN driver tells of bus-off with an error frame (CAN_ERR_BUSOFF); on
# vcan0 cansend injects one, and every raw socket with an error mask receives it: the
# simulated board's (`mjc sim` stands its link for the board's controller; the virtual
# G474 board turns it into its FDCAN's own bus-off) and the tools'. During a trial:
#   - the board stops the motion, sends its Fault frame (0x011 for node 1) with code
#     303 (0x012F), counts the bus-off, and keeps talking (it recovered);
#   - mjc trial says bus-off on stderr at once, and ends with exit 5 naming fault 303;
#   - mjc monitor, running meanwhile, says bus-off too;
#   - mjc clear clears the fault (its cause is gone) and the next trial completes.
# A cause that stays: the joint encoder flags an error (the board's SIGUSR1); mjc clear
# is refused (exit 4, naming fault 101) until the flag is gone, then accepted.
# The interface down for two seconds mid-trial: the board rides through and faults 302;
# once it is up, mjc clear and the next trial work.
# The board is `mjc sim`, or the one MJC_BOARD names (board.sh).
# usage: [MJC_BOARD=<board command>] faults.sh <path of mjc>
set -u
mjc=$1
work=$(mktemp -d)
. "$(dirname "$0")/checks.sh"
. "$(dirname "$0")/receivers.sh"
. "$(dirname "$0")/board.sh"

# The plant's own slack (sim_host/params/default.json), so no sweep is needed.
cat >"$work/cal.json" <<'JSON'
{"c_right_deg": 1.1001, "c_left_deg": -0.8995, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
"${board[@]}" --iface vcan0 --node 1 --subject subject1 --speed 1 2>"$work/sim.err" &
sim=$!
check "the simulated board comes up" wait_board "$work/sim.err" 1
check "calibration upload" "$mjc" cal upload "$work/cal.json" --iface vcan0 --node 1

count_receivers
base=$receivers
stdbuf -oL candump -L vcan0,011:7FF >"$work/fault.log" 2>&1 &
dumper=$!
"$mjc" monitor --iface vcan0 --node 1 --interval-ms 200 \
  >"$work/monitor.out" 2>"$work/monitor.err" &
monitor=$!
"$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 20 \
  --frequency-hz 0.5 --rest-s 0.2 --out "$work/trial" --no-figure >"$work/trial.out" 2>"$work/trial.err" &
trial=$!
wait_receivers $((base + 3))  # candump, monitor, trial
check "the trial runs" wait_for "$work/trial.err" "repetition 1/20" "$trial"

cansend vcan0 20000040#0000000000000000  # CAN_ERR_FLAG | CAN_ERR_BUSOFF
wait "$trial"
check_exit $? 5 "mjc trial ends with exit 5, the board faulted"
check "mjc trial says bus-off at once" grep -q "mjc trial: vcan0: the CAN controller reported bus-off (1 since start)" "$work/trial.err"
check "mjc trial names fault 303" grep -q "fault 303 (CAN bus-off)" "$work/trial.err"
check "the board says bus-off" wait_for "$work/sim.err" "$board_name: vcan0: bus-off at"
check "the board's Fault frame carries 303 (0x012F)" wait_for "$work/fault.log" "vcan0 011#2F01"
check "mjc monitor says bus-off at once" wait_for "$work/monitor.err" "mjc monitor: vcan0: the CAN controller reported bus-off"
check "mjc monitor shows the latched fault" wait_for "$work/monitor.out" "  fault 303 (CAN bus-off)"
check "mjc monitor counts the bus-off" wait_for "$work/monitor.out" "vcan0: 1 error frames since start, 1 of them bus-off (BUS-OFF)"
kill -INT "$monitor"
wait "$monitor"

# The board recovered (it still answers) and its cause is gone: an explicit clear works.
"$mjc" clear --iface vcan0 --node 1 >"$work/clear.out" 2>"$work/clear.err"
check_exit $? 0 "mjc clear exits 0"
check "mjc clear says what it cleared" grep -q "node 1: fault 303 (CAN bus-off) cleared" "$work/clear.out"
"$mjc" clear --iface vcan0 --node 1 >"$work/clear2.out" 2>&1
check "a second clear finds nothing latched" grep -q "node 1: no fault latched" "$work/clear2.out"
"$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 3 \
  --frequency-hz 2 --rest-s 0.2 --out "$work/after" --no-figure >"$work/after.out" 2>"$work/after.err"
check_exit $? 0 "the next trial completes"
"$mjc" stop --iface vcan0 --node 1 >"$work/stop.out" 2>&1
check "mjc stop is answered" grep -q "node 1 stopped" "$work/stop.out"
"$mjc" clear --iface vcan0 --node 2 --timeout-ms 300 >"$work/silent.out" 2>"$work/silent.err"
check_exit $? 3 "mjc clear of an absent node exits 3"
check "and says why" grep -q "mjc clear: node 2 is silent (is the board powered and on vcan0? try mjc list)" "$work/silent.err"

# A cause that stays: the joint encoder flags an error (the board's SIGUSR1) at rest.
kill -USR1 "$sim"
check "the board says the encoder flags an error" wait_for "$work/sim.err" "joint encoder error flag raised"
"$mjc" monitor --iface vcan0 --node 1 --interval-ms 200 >"$work/ef.out" 2>&1 &
monitor=$!
check "the board latched fault 101" wait_for "$work/ef.out" "fault 101 (joint encoder error flag)"
kill -INT "$monitor"
wait "$monitor"
"$mjc" clear --iface vcan0 --node 1 >"$work/refused.out" 2>"$work/refused.err"
check_exit $? 4 "mjc clear while the cause is present exits 4"
check "and names the fault still held" grep -q "mjc clear: node 1: fault 101 (joint encoder error flag) not cleared: its cause is still present" "$work/refused.err"
kill -USR2 "$sim"
check "the encoder recovers" wait_for "$work/sim.err" "joint encoder error flag cleared"
"$mjc" clear --iface vcan0 --node 1 >"$work/cleared.out" 2>&1
check_exit $? 0 "once it is gone, mjc clear exits 0"
check "and says what it cleared" grep -q "node 1: fault 101 (joint encoder error flag) cleared" "$work/cleared.out"

codes=$(sed -n 's/.* 011#\(....\).*/\1/p' "$work/fault.log" | tr '\n' ' ')
check "the board sent two Fault frames, 303 then 101 (codes $codes)" test "$codes" = "2F01 6500 "

# The interface down for two seconds mid-trial, then up (a cable pulled and plugged back;
# `ip link set vcan0 down`): the board rides through without its bus and stops the
# orphaned motion on its host timeout (fault 302); mjc trial ends saying the link went
# down; once it is up, the board answers, mjc clear clears 302 and a trial completes.
"$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 20 \
  --frequency-hz 0.5 --rest-s 0.2 --out "$work/down" --no-figure >"$work/down.out" 2>"$work/down.err" &
trial=$!
check "a trial runs before the link goes down" wait_for "$work/down.err" "repetition 1/20" "$trial"
ip link set vcan0 down
sleep 2  # the outage itself, not a wait for an outcome
ip link set vcan0 up
wait "$trial"
check_exit $? 1 "mjc trial ends with exit 1, its link gone"
# (Its receive says the interface went down, or a heartbeat's send found it down first.)
check "  saying the interface went down" grep -qE "'vcan0' went down|cannot send on 'vcan0': Network is down" "$work/down.err"
check "  and that the board stops the motion itself" \
  grep -q "node 1 stops the motion itself when it misses this host's heartbeats (fault 302)" "$work/down.err"
check "the board said it went down" wait_for "$work/sim.err" "$board_name: vcan0 went down at"
check "  and up again" wait_for "$work/sim.err" "$board_name: vcan0 is up again at"
check "  and is still running" kill -0 "$sim"
# The orphaned motion's stop comes a host timeout of the board's time after the last
# heartbeat, which a board slower than real time may reach only after the outage.
"$mjc" monitor --iface vcan0 --node 1 --interval-ms 200 >"$work/orphan.out" 2>&1 &
monitor=$!
check "the board stopped the orphaned motion: fault 302" \
  wait_for "$work/orphan.out" "fault 302 (host heartbeat lost)" "$monitor"
kill -INT "$monitor"
wait "$monitor"
"$mjc" clear --iface vcan0 --node 1 >"$work/clear3.out" 2>"$work/clear3.err"
check_exit $? 0 "mjc clear exits 0 once the link is up"
check "  clearing the orphaned motion's fault 302" grep -q "node 1: fault 302 (host heartbeat lost) cleared" "$work/clear3.out"
"$mjc" trial --iface vcan0 --node 1 --protocol amplitude --amplitudes 15 --reps 3 \
  --frequency-hz 2 --rest-s 0.2 --out "$work/after_down" --no-figure >"$work/after_down.out" 2>"$work/after_down.err"
check_exit $? 0 "a trial completes after the outage"

kill -INT "$sim"
wait "$sim"
kill "$dumper" 2>/dev/null
wait "$dumper" 2>/dev/null
check "the board counted one bus-off" grep -q "bus-off 1$" "$work/sim.err"

finish "$work/sim.err" "$work/trial.err" "$work/monitor.out" "$work/monitor.err" \
  "$work/fault.log" "$work/clear.out" "$work/clear.err" "$work/down.err" "$work/clear3.err"
