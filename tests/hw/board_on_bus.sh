#!/bin/bash
# A real joint board on a real bus (ctest label hw): it answers, reports its build,
# calibrates and runs a short trial. ctest skips it (status 77) unless MJC_HW_CAN names
# the interface the board is on (`MJC_HW_CAN=can0 ctest --test-dir build/host -L hw`).
#
# THE JOINT MOVES: run it with the robot alone — nobody's finger in the device — as for
# any calibration (README, "A lab session").
#
# usage: board_on_bus.sh <path of mjc>
# environment: MJC_HW_CAN (required), MJC_HW_NODE (default 1), MJC_HW_BUILD (the build
# the board should run, e.g. the short commit of the image flashed; unchecked if unset),
# MJC_HW_PROBE=1 when an ST-Link is on the board's SWD connector: the chip's option
# bytes, clock source, reset flags and FDCAN transmitter delay are then read through
# OpenOCD, without halting the core (chip_registers.sh)
#
# The kernel layer runs this same script against a simulated board on vcan0
# (kernel_hw_script), so what a lab runs on its first board has been run before.
set -u
mjc=$1
if [ -z "${MJC_HW_CAN:-}" ]; then
  echo "skipped: set MJC_HW_CAN to the CAN interface a joint board is on (robot alone)"
  exit 77
fi
iface=$MJC_HW_CAN
node=${MJC_HW_NODE:-1}
work=$(mktemp -d)
. "$(dirname "$0")/../kernel/checks.sh"
echo "joint board, node $node on $iface (work folder $work)"

# A number from a JSON file with its key once in it.
json_number() {  # FILE KEY
  sed -n "s/.*\"$2\": *\([-+0-9.eE]*\).*/\1/p" "$1" | head -n 1
}
# KEY...: the fitted file and the board's copy agree on each (fixed point on the board).
same_number() {
  local key a b
  for key in "$@"; do
    a=$(json_number "$work/cal/calibration.json" "$key")
    b=$(json_number "$work/board.json" "$key")
    echo "$key: fitted ${a:-?}, board ${b:-?}"
    awk -v a="$a" -v b="$b" 'BEGIN { exit !(a != "" && b != "" && (a - b)^2 < 0.001^2) }' ||
      return 1
  done
}

# It answers and says what it runs: the application (not the bootloader), idle, no fault.
"$mjc" list --iface "$iface" --json >"$work/list.json" 2>"$work/list.err"
status=$?
check "mjc list hears the bus (exit $status)" test "$status" -eq 0
line=$(grep "\"node\": *$node[,}]" "$work/list.json" | head -n 1)
echo "node $node: ${line:-not heard}"
check "node $node answers" test -n "$line"
check "  running its application" grep -q '"image": *"application"' <<<"$line"
check "  with a build id" grep -qE '"build": *"[0-9a-f]{7,}' <<<"$line"
if [ -n "${MJC_HW_BUILD:-}" ]; then
  check "  the build flashed ($MJC_HW_BUILD)" grep -q "\"build\": *\"$MJC_HW_BUILD" <<<"$line"
fi
check "  not faulted" grep -q '"fault": *null' <<<"$line"
cause=$(sed -n 's/.*"reset_cause": *"\([^"]*\)".*/\1/p' <<<"$line")
echo "  last reset: ${cause:-not reported}"
check "  with a known reset cause" test -n "$cause" -a "$cause" != unknown

# The chip through the probe (docs/BRINGUP.md): the option bytes first-flash set, the
# clock the image runs on, the reset flags, the transceiver's loop delay as FDCAN1
# measured it on the node's own fast data phases.
if [ "${MJC_HW_PROBE:-0}" = 1 ]; then
  registers=$(dirname "$0")/chip_registers.sh
  check "registers read through the probe (openocd mdw, core running)" \
    "$registers" read "$work/registers.txt"
  for what in optr clock reset tdc; do
    "$registers" "$what" "$work/registers.txt" | sed 's/^/  /'
  done
  check "  FLASH_OPTR: nSWBOOT0 = 0, nBOOT0 = 1, DBANK = 1" \
    "$registers" optr "$work/registers.txt"
  check "  clock: SYSCLK from the PLL, the PLL from the HSE (HSERDY)" \
    "$registers" clock "$work/registers.txt"
  check "  RCC_CSR read" "$registers" reset "$work/registers.txt"
  check "  FDCAN1 measured a transmitter delay (0 < TDCV - TDCO, TDCV < 127)" \
    "$registers" tdc "$work/registers.txt"
else
  echo "registers through a probe: skipped (MJC_HW_PROBE=1 with an ST-Link on SWD)"
fi

# A short calibration: sweep, fit, upload, and the board keeping it. 1.5 Hz: at 2 Hz the
# 30° sweep moves the bare joint at up to 5.2 rad/s, past the board's 5 rad/s velocity
# limit (fault 203).
check "mjc calibrate (sweep, fit, upload)" \
  "$mjc" calibrate --iface "$iface" --node "$node" --frequency-hz 1.5 --cycles 6 \
  --out "$work/cal"
check "  the board gives it back" \
  "$mjc" cal download --iface "$iface" --node "$node" --out "$work/board.json"
check "  as fitted (c_r, c_l within 0.001°)" same_number c_right_deg c_left_deg

# A short trial on the robot alone: three repetitions at 6°, every window reported.
check "mjc trial (6°, 3 repetitions)" \
  "$mjc" trial --iface "$iface" --node "$node" --trials 1 --reps 3 --amplitude-deg 6 \
  --rest-s 0.5 --out "$work/trial" --no-figure
check "  3 flexion and 3 extension windows" \
  sh -c "test \$(grep -c ',flexion,' '$work/trial/windows.csv') -eq 3 &&
         test \$(grep -c ',extension,' '$work/trial/windows.csv') -eq 3"

finish "$work/list.err"
