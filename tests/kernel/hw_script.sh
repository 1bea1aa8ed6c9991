#!/bin/bash
# The hardware script (tests/hw/board_on_bus.sh) against a simulated board on vcan0,
# run inside the VM by scripts/kernel-vm: what a lab runs on its first real board has
# run here first, with the same mjc and the same checks.
# usage: hw_script.sh <path of mjc>
set -u
mjc=$1
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
work=$(mktemp -d)
. "$here/checks.sh"

"$mjc" sim --iface vcan0 --node 3 2>"$work/sim.err" &
sim=$!
if ! wait_for "$work/sim.err" "mjc sim: node 3 on vcan0"; then
  kill "$sim" 2>/dev/null
  exit 1
fi
# The build the board must report: the one this mjc was built from (mjc sim runs the
# same tree's application).
build=$("$mjc" --version | sed -n 's/.* \([0-9a-f]\{7,\}\).*/\1/p' | head -n 1)
MJC_HW_CAN=vcan0 MJC_HW_NODE=3 MJC_HW_BUILD=$build "$here/../hw/board_on_bus.sh" "$mjc"
status=$?
kill -INT "$sim" 2>/dev/null
wait "$sim"
exit "$status"
