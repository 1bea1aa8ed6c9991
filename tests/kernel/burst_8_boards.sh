#!/bin/bash
# Eight simulated boards at their full default rates (1 kHz angles each, twice real time:
# ~17,000 frames/s on one vcan0) while mjc log records: every frame a board sent is
# either received by the logger or counted as dropped by the kernel; none vanishes.
# usage: burst_8_boards.sh <path of mjc>
set -u
mjc=$1
work=$(mktemp -d)

# The logger is ready once the CAN core has registered its receiver on vcan0.
. "$(dirname "$0")/receivers.sh"
# Frames the input backlog drops count as the kernel's drops (receivers.sh).
backlog_before=$(backlog_dropped)

count_receivers
base=$receivers
"$mjc" log --iface vcan0 --out "$work/bus.log" 2>"$work/log.err" &
logger=$!
if ! wait_receivers $((base + 1)); then
  echo "FAIL the logger never listened: $(cat "$work/log.err")"
  echo "0 passed, 1 failed"
  exit 1
fi
pids=()
# 6 s of each application at full rate: --seconds is board time from power-on, and the
# first 0.2 s of it are the bootloader's hold window.
for node in 1 2 3 4 5 6 7 8; do
  "$mjc" sim --iface vcan0 --node "$node" --speed 2 --seconds 6.2 2>"$work/sim$node.err" &
  pids+=($!)
done
wait "${pids[@]}"
# Every board frame in the logger's socket before it stops (receivers.sh); on SIGINT
# the logger writes what its socket holds.
if ! why=$(flush_bus); then
  echo "FAIL $why"
  echo "0 passed, 1 failed"
  exit 1
fi
kill -INT "$logger" 2>/dev/null
wait "$logger"
sent=0
for node in 1 2 3 4 5 6 7 8; do
  n=$(sed -n 's/.*frames sent \([0-9]*\).*/\1/p' "$work/sim$node.err")
  echo "node $node sent ${n:-?}"
  sent=$((sent + ${n:-0}))
done
logged=$(grep -cv " $bus_marker#" "$work/bus.log")
dropped=$(sed -n 's/.*frames, \([0-9]*\) dropped.*/\1/p' "$work/log.err")
backlog=$(($(backlog_dropped) - backlog_before))
echo "sent $sent, logged $logged, dropped by the kernel ${dropped:-?} at the socket," \
  "$backlog in the input backlog"
dropped=$((${dropped:-0} + backlog))
passed=0
failed=0
if [ "$sent" -gt 50000 ] && [ "$sent" -eq $((logged + dropped)) ]; then
  echo "PASS every frame of 8 boards accounted for"; passed=1
else
  echo "FAIL frames unaccounted for"; failed=1
fi
echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
