#!/bin/bash
# Firmware updates over vcan0 in Debian's kernel (run inside the VM by
# scripts/kernel-vm): mjc flash, the kernel's ISO-TP, and two simulated boards, each
# running its bootloader's logic over its own flash file before its application.
#
#   - bad files and flags: one line, a non-zero exit, and not a frame on the bus;
#   - two boards, calibrated (each its own calibration), take a 64 KB image of a new
#     build in one mjc flash; board 2 loses power in the middle of its upload (kill -9
#     of its mjc sim once the board itself reports 40 % programmed), so mjc flash names
#     it and exits 8 while board 1 goes through;
#   - board 2 powered up again on its flash (without --node: its identity record names
#     it) stays in its bootloader, says why, and mjc list and mjc flash --info show it;
#     a second mjc flash ends its update;
#   - both run the new build, with their calibration and node id as they were.
# Every wait is for an event (checks.sh); the boards keep real time (--speed 1) and mjc
# flash's own waits follow their clocks. Prints flash_upload_s_64k, board 1's upload
# (a figure, not a check).
# usage: flash_update.sh <path of mjc> <path of mjc-image>
set -u
mjc=$(realpath "$1")
packer=$(realpath "$2")
work=$(mktemp -d)
. "$(dirname "$0")/checks.sh"
. "$(dirname "$0")/receivers.sh"
cd "$work" || exit 1

# The new firmware: 64 KB with a vector table for the joint board (the stack's top in
# SRAM, a Thumb reset handler inside), packed as the build packs the board's image,
# for a build no board runs yet.
new=5eed1234
{
  printf '\x00\x80\x01\x20\x01\x44\x00\x08'
  yes "maestro-jc test image $new" | head -c $((65536 - 8))
} >app.raw
pack() {  # OUT [more mjc-image options]
  local out=$1
  shift
  "$packer" pack app.raw "$out" --hardware 1 1 --load-address 0x08004200 --commit $new \
    --dirty 0 --commit-time 1795486377 --describe "test-$new" "$@" >/dev/null
}
check "the new image packs" pack new.bin --board-type 1
pack qemu.bin --board-type 2
pack flipped.bin --board-type 1 --flip-byte 30000
head -c 40000 new.bin >truncated.bin

# Refusals, with a candump listening: nothing may reach the bus.
count_receivers
base=$receivers
stdbuf -oL candump -L vcan0 >refusals.log 2>&1 &
dumper=$!
wait_receivers $((base + 1))
check "another board's image: one line, exit 1" \
  refuses 1 qemu.err "$mjc" flash --iface vcan0 --node 1 qemu.bin
check "  naming the board it is for" grep -q "qemu.bin: built for QEMU's mps2-an386 test board (board type 2), not the joint board (board type 1)" qemu.err
check "a truncated file: one line, exit 1" refuses 1 cut.err "$mjc" flash --iface vcan0 --all truncated.bin
check "  saying so" grep -q "truncated.bin: truncated: 40000 bytes, its header says 512 + 65536 = 66048" cut.err
check "a corrupted image: one line, exit 1" refuses 1 crc.err "$mjc" flash --iface vcan0 --node 2 flipped.bin
check "  naming the CRC" grep -q "flipped.bin: corrupted: the image's CRC-32 is 0x" crc.err
check "no file: one line, exit 1" refuses 1 none.err "$mjc" flash --iface vcan0 --node 2 none.bin
check "no boards named: one line, exit 2" refuses 2 which.err "$mjc" flash --iface vcan0 new.bin
check "a node out of range: one line, exit 2" refuses 2 range.err "$mjc" flash --iface vcan0 --node 9 new.bin
kill "$dumper"
wait "$dumper" 2>/dev/null
check "  and not a frame went on the bus" test ! -s refusals.log

# Two boards, each with its own calibration. Their flash files in the VM's memory: on
# the host's share (9p) every double-word programmed was a round trip to the host, which
# set the upload's pace.
mkdir ram && mount -t tmpfs none ram || exit 1
"$mjc" sim --iface vcan0 --node 1 --flash ram/b1.flash 2>sim1.err &
sim1=$!
"$mjc" sim --iface vcan0 --node 2 --flash ram/b2.flash 2>sim2.err &
sim2=$!
check "board 1 comes up" wait_for sim1.err "mjc sim: node 1 on vcan0"
check "board 2 comes up" wait_for sim2.err "mjc sim: node 2 on vcan0"
cat >cal1.json <<'JSON'
{"c_right_deg": 1.1001, "c_left_deg": -0.8995, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
cat >cal2.json <<'JSON'
{"c_right_deg": 0.9502, "c_left_deg": -1.2003, "alpha": 1.1, "sea_stiffness_Nm_per_rad": 0.58, "joint_zero_count": 4021}
JSON
check "board 1 takes its calibration" "$mjc" cal upload cal1.json --iface vcan0 --node 1
check "board 2 takes its calibration" "$mjc" cal upload cal2.json --iface vcan0 --node 2
for n in 1 2; do
  check "board $n's calibration reads back" \
    "$mjc" cal download --iface vcan0 --node $n --out before$n.json
done
build=$("$mjc" --version | sed -n 's/^mjc .* (build \([0-9a-f]\{8\}\)\(+dirty\)\{0,1\})$/\1/p')
"$mjc" flash --iface vcan0 --info >info1.out 2>info1.err
check_exit $? 0 "mjc flash --info lists both"
check "  running their application with mjc's build" \
  sh -c "grep -qE '^ +1  application  $build' info1.out && grep -qE '^ +2  application  $build' info1.out"

# Board 2's bootloader reports its progress (BootStatus, 0x382: bytes 2-3 permille).
count_receivers
base=$receivers
stdbuf -oL candump -L vcan0,382:7FF >progress2.log 2>&1 &
dumper=$!
wait_receivers $((base + 1))
# PERMILLE: waits until node 2's last BootStatus reports at least that much programmed.
wait_progress() {
  local i line data
  local end=$((SECONDS + ${MJC_WAIT_CAP_S:-300}))
  while ((SECONDS < end)); do
    line=
    while IFS= read -r l; do line=$l; done <progress2.log
    data=${line##*#}
    if ((${#data} == 16)) && ((16#${data:6:2}${data:4:2} >= $1)); then
      echo "board 2 reports ${data:6:2}${data:4:2} (hex) permille"
      return 0
    fi
    sleep 0.05
  done
  echo "node 2 never reported $1 permille: ${line:-nothing}"
  return 1
}
"$mjc" flash --iface vcan0 --node 1 --node 2 new.bin >flash1.out 2>flash1.err &
flash=$!
check "board 2 reports 40 % of its upload" wait_progress 400
kill -9 "$sim2"  # a power cut
wait "$sim2" 2>/dev/null
wait "$flash"
check_exit $? 8 "mjc flash exits 8: a board was not updated"
check "  board 1 was: its new build, checked by the board" \
  grep -qE "^node 1: updated to $new \(test-$new\) in [0-9.]+ s: 64.0 KB sent in [0-9.]+ s .*checked by the board" flash1.out
check "  board 2 is named: silent in the upload, run mjc flash again" \
  grep -q "mjc flash: node 2 went silent during the upload (.* programmed): a power cut or a reset? .*run mjc flash again" flash1.err
check "  and the summary says which" grep -q "^mjc flash: 1 of 2 boards not updated (node 2; see above), the others run $new" flash1.err
kill "$dumper"
wait "$dumper" 2>/dev/null
seconds=$(sed -n "s/^node 1: updated .*: 64.0 KB sent in \([0-9.]*\) s .*/\1/p" flash1.out)

# Power back on, same flash, no --node: the identity record names it.
"$mjc" sim --iface vcan0 --flash ram/b2.flash 2>sim2b.err &
sim2=$!
check "board 2 comes up in its bootloader, saying why" \
  wait_for sim2b.err "mjc sim: node 2: bootloader stays: ready (no valid image: no_image)"
"$mjc" list --iface vcan0 >list2.out 2>list2.err
status=$?
check "mjc list (exit $status): board 2 in its bootloader, ready, no valid image" \
  grep -qE "^ +2  bootloader   $build.* ready .* stays: no valid image \(no_image\)" list2.out
check "  board 1 runs $new" grep -qE "^ +1  application  $new" list2.out
"$mjc" flash --iface vcan0 --info --json >info2.json 2>info2.err
check "mjc flash --info --json: board 2 in its bootloader" \
  jq -se 'map(select(.node == 2))[0] | .image == "bootloader" and .boot.reason == "no valid image"' info2.json
"$mjc" flash --iface vcan0 --node 2 new.bin >flash2.out 2>flash2.err
check_exit $? 0 "a second mjc flash ends board 2's update"
check "  with its new build" grep -qE "^node 2: updated to $new" flash2.out
check "board 2 starts the new image" wait_for sim2b.err "mjc sim: node 2 on vcan0 (default, robot alone): build $new"

"$mjc" list --iface vcan0 --json >list3.json 2>list3.err
check "both run $new, their application" \
  jq -se "length == 2 and all(.[]; .image == \"application\" and .build == \"$new\" and .calibrated)" list3.json
for n in 1 2; do
  "$mjc" cal download --iface vcan0 --node $n --out after$n.json 2>after$n.err
  check "board $n kept its calibration" cmp before$n.json after$n.json
done
check "board 2's calibration is its own" sh -c "! cmp -s after1.json after2.json"

echo "flash_upload_s_64k: ${seconds:-none} s (board 1's 64 KB over ISO-TP on vcan0, in the VM beside board 2's application)"
kill "$sim1" "$sim2" 2>/dev/null
wait "$sim1" "$sim2" 2>/dev/null
umount ram
finish sim1.err sim2.err sim2b.err flash1.err info2.json info2.err
