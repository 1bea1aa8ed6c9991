#!/bin/sh
# mjc's --hand and --joint without a bus (label unit): a joint resolves to its node id
# (seen in mjc reset's refusal, which names the node), to its robot description (seen
# in mjc calibrate's travel check, which names the description) and to the hand's
# interface (seen in the refusal of a hand wired to lo); each misuse is one line and
# exit 2 (or 1 for a hand file that is refused).
# usage: mjc_hand.sh <path of mjc> <source tree> <scratch folder>
set -u
mjc=$1
src=$2
work=$3
rm -rf "$work"
mkdir -p "$work"
cd "$work" || exit 1
hand=$src/hands/maestro-right.json
passed=0
failed=0
# DESCRIPTION STATUS TEXT COMMAND...: the command exits STATUS with one line on stderr
# holding TEXT.
refuses() {
  what=$1 want=$2 text=$3
  shift 3
  "$@" >/dev/null 2>err.txt
  got=$?
  if [ "$got" -eq "$want" ] && [ "$(wc -l <err.txt)" -eq 1 ] &&
    grep -qF -- "$text" err.txt; then
    echo "PASS $what"
    passed=$((passed + 1))
  else
    echo "FAIL $what: exit $got (want $want): $(cat err.txt)"
    failed=$((failed + 1))
  fi
}

refuses "--joint index_mcp is node 4" 2 "no reset line for node 4:" \
  "$mjc" reset --hand "$hand" --joint index_mcp
refuses "--joint ring_little_mcp is node 8" 2 "no reset line for node 8:" \
  "$mjc" reset --hand "$hand" --joint ring_little_mcp
refuses "an unknown joint is refused with the hand's joints" 2 \
  "mjc reset: --joint indx_mcp: $hand has no such joint (did you mean 'index_mcp'?); its joints: thumb_cmc, thumb_mcp, thumb_ip, index_mcp, index_pip, middle_mcp, middle_pip, ring_little_mcp" \
  "$mjc" reset --hand "$hand" --joint indx_mcp
refuses "--node with --joint is refused" 2 "--node and --joint together" \
  "$mjc" reset --hand "$hand" --joint index_mcp --node 2
refuses "--node with --hand is refused" 2 "--node and --hand together" \
  "$mjc" monitor --hand "$hand" --node 2
refuses "--hand alone where one node is taken" 2 "name the joint too (--joint NAME" \
  "$mjc" reset --hand "$hand"
refuses "two joints where one node is taken" 2 "one --joint" \
  "$mjc" reset --hand "$hand" --joint index_mcp --joint index_pip
refuses "--joint without a hand" 2 "--joint needs a hand" \
  "$mjc" reset --joint index_mcp
refuses "an unknown joint among several" 2 "--joint nope: $hand has no such joint" \
  "$mjc" stop --hand "$hand" --joint index_mcp --joint nope

# The config file's hand, its path from the config file's folder.
mkdir -p lab/hands
cp "$hand" lab/hands/right.json
sed -i "s#\"\.\./robots/#\"$src/robots/#" lab/hands/right.json
printf '{"hand": "hands/right.json"}\n' >lab/config.json
refuses "the config file's hand: --joint thumb_ip is node 3" 2 "no reset line for node 3:" \
  env MJC_CONFIG="$work/lab/config.json" "$mjc" reset --joint thumb_ip
sed 's/"thumb_ip"/"thumb_distal"/' lab/hands/right.json >lab/hands/other.json
refuses "a --hand wins over the config file's" 2 "lab/hands/other.json has no such joint" \
  env MJC_CONFIG="$work/lab/config.json" "$mjc" reset --hand lab/hands/other.json \
  --joint thumb_ip
printf '{"hand": 3}\n' >lab/bad-config.json
refuses "a config file's hand that is not a path" 1 "'hand' must be the path of a hand file" \
  env MJC_CONFIG="$work/lab/bad-config.json" "$mjc" reset --joint thumb_ip

# --joint supplies the joint's description: index_mcp's is example-alpha-1.25 (α 1.25,
# travel -45..75°), whose travel 70° of sweep leaves.
refuses "--joint gives calibrate the joint's description" 2 \
  "moves example-alpha-1.25's joint ±87.5° (α 1.250), beyond its travel [-45.0°, 75.0°]" \
  "$mjc" calibrate --hand "$hand" --joint index_mcp --amplitude-deg 70
refuses "--robot naming the same file is accepted" 2 "moves example-alpha-1.25's joint" \
  "$mjc" calibrate --hand "$hand" --joint index_mcp --amplitude-deg 70 \
  --robot "$src/robots/../robots/example-alpha-1.25.json"
refuses "--robot naming another file is refused" 2 \
  "is not the description of joint 'index_mcp' in $hand" \
  "$mjc" trial --hand "$hand" --joint index_mcp --robot "$src/robots/maestro-default.json"
refuses "--fit-alpha without a description" 2 "--fit-alpha needs the joint's description" \
  "$mjc" calibrate --fit-alpha

# A hand file that is refused: exit 1, naming the file and the joint.
sed 's/"torque_Nm": 0.8/"torque_Nm": 1.5/' lab/hands/right.json >lab/hands/strong.json
refuses "a hand refused names the joint and the reason" 1 \
  "hand refused: lab/hands/strong.json: joint 'index_mcp': field 'subject.torque_Nm' = 1.5 N·m is above the torque limit 1 N·m" \
  "$mjc" stop --hand lab/hands/strong.json --joint thumb_cmc
refuses "mjc list refuses it too" 1 "hand refused: lab/hands/strong.json" \
  "$mjc" list --hand lab/hands/strong.json

# The hand's interface is the default --iface (here lo, which is no CAN interface).
if [ -r /sys/class/net/lo/type ]; then
  sed 's/"iface": "can0"/"iface": "lo"/' lab/hands/right.json >lab/hands/lo.json
  refuses "the hand's iface" 1 "'lo' is not a CAN interface" \
    "$mjc" stop --hand lab/hands/lo.json --joint thumb_cmc
  refuses "the hand's iface, for mjc list" 1 "'lo' is not a CAN interface" \
    "$mjc" list --hand lab/hands/lo.json
  # Whatever this machine says of nonexistent0, it is not about lo.
  "$mjc" stop --hand lab/hands/lo.json --joint thumb_cmc --iface nonexistent0 \
    >/dev/null 2>err.txt
  if [ -s err.txt ] && ! grep -q "'lo'" err.txt; then
    echo "PASS --iface wins over the hand's"
    passed=$((passed + 1))
  else
    echo "FAIL --iface wins over the hand's: $(cat err.txt)"
    failed=$((failed + 1))
  fi
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ]
