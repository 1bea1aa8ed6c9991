#!/bin/bash
# mjc list --hand and --joint against simulated boards on vcan0 (run inside the VM by
# scripts/kernel-vm): with boards on nodes 1 and 2, a hand of joints on nodes 1, 2 and
# 3 is incomplete (node 3 named missing, exit 3), one of nodes 1 and 2 complete (exit
# 0, its --json object read by jq), and a board the hand does not have is named extra;
# mjc stop reaches every joint of the hand (--hand alone) and a joint by its name
# (--joint), on the hand's interface. Every wait is for an event (checks.sh).
# usage: hand_list.sh <path of mjc>
set -u
mjc=$(realpath "$1")
robots=$(realpath "$(dirname "$0")/../../robots")
work=$(mktemp -d)
. "$(dirname "$0")/checks.sh"
cd "$work" || exit 1

# HAND NAME:NODE...: a hand file on vcan0 whose joints all use the default description.
hand() {
  local file=$1 joints= sep=
  shift
  for j in "$@"; do
    joints+="$sep{\"name\": \"${j%%:*}\", \"node\": ${j##*:}, \"robot\": \"$robots/maestro-default.json\", \"subject\": {\"extension_deg\": -30, \"flexion_deg\": 80, \"torque_Nm\": 0.8, \"energy_per_window_mJ\": 500}}"
    sep=", "
  done
  echo "{\"name\": \"${file%.json}\", \"iface\": \"vcan0\", \"joints\": [$joints]}" >"$file"
}
hand three.json index_mcp:1 index_pip:2 middle_mcp:3
hand two.json index_mcp:1 index_pip:2
hand one.json index_pip:2

"$mjc" sim --iface vcan0 --node 1 2>sim1.err &
sim1=$!
"$mjc" sim --iface vcan0 --node 2 2>sim2.err &
sim2=$!
check "board 1 comes up" wait_for sim1.err "mjc sim: node 1 on vcan0"
check "board 2 comes up" wait_for sim2.err "mjc sim: node 2 on vcan0"

"$mjc" list --hand three.json >three.out 2>three.err
check_exit $? 3 "mjc list --hand: a joint missing"
check "  node 1 present" grep -qE "^  index_mcp +node 1  present$" three.out
check "  node 3 missing" grep -qE "^  middle_mcp +node 3  missing$" three.out
check "  the verdict" grep -qx "  three: incomplete, 2 of 3 joints: missing middle_mcp" three.out
check "  one line on stderr naming it" \
  grep -qx "mjc list: three is incomplete: no board answers for middle_mcp (node 3)" three.err

"$mjc" list --hand two.json --json >two.json.out 2>two.err
check_exit $? 0 "mjc list --hand: every joint present"
check "  its --json object, read by jq" \
  jq -se '.[-1] | .hand == "two" and .complete and (.joints | map(.present) == [true, true]) and .extra == [] and .wrong_build == []' two.json.out

"$mjc" list --hand one.json >one.out 2>one.err
check_exit $? 0 "mjc list --hand: a board the hand does not have"
check "  is named extra" grep -qx "  node 1: extra, not a joint of one" one.out

check "mjc stop --hand: every joint" "$mjc" stop --hand two.json
check "mjc stop --joint: one joint by name" "$mjc" stop --hand two.json --joint index_pip

kill "$sim1" "$sim2" 2>/dev/null
wait "$sim1" "$sim2" 2>/dev/null
finish sim1.err sim2.err
