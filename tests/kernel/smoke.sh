#!/bin/bash
# Kernel-layer smoke test: real SocketCAN on vcan0 with can-utils, the ground the host
# tools stand on. Runs inside the kernel-vm guest (scripts/kernel-vm run smoke.sh),
# which creates vcan0 with MTU 72; it also runs on any Linux with such a vcan0.
#
# One line per check, then "N passed, N failed"; exits 1 when any check failed.
set -u

readonly dev=vcan0
pass=0
fail=0
work=$(mktemp -d "${TMPDIR:-/tmp}/kernel-smoke.XXXXXX")
trap 'jobs -p | xargs -r kill 2>/dev/null; rm -rf "$work"' EXIT

report() {  # NAME STATUS DETAIL
  if [[ $2 == 0 ]]; then
    echo "PASS $1"
    pass=$((pass + 1))
  else
    echo "FAIL $1: $3"
    fail=$((fail + 1))
  fi
}

. "$(dirname "$0")/receivers.sh"

# Space-separated upper-case hex bytes of a deterministic pattern, N bytes long.
# (printf -v, not $(...): a fork per byte costs seconds under TCG.)
pattern() {
  local i byte out=()
  for ((i = 0; i < $1; i++)); do
    printf -v byte '%02X' $(((i * 7 + 3) & 0xff))
    out+=("$byte")
  done
  echo "${out[*]}"
}

# Starts `candump ARGS $dev` in the background writing to FILE; returns once it listens.
start_candump() {  # FILE ARGS...
  local file=$1 base
  shift
  count_receivers
  base=$receivers
  timeout "${MJC_WAIT_CAP_S:-300}" candump "$@" "$dev" >"$file" 2>&1 &
  wait_receivers $((base + 1))
}

if ! ip link show "$dev" >/dev/null 2>&1; then
  echo "FAIL setup: no $dev (run inside scripts/kernel-vm, which creates it)"
  echo "0 passed, 1 failed"
  exit 1
fi
[[ $(cat "/sys/class/net/$dev/mtu") == 72 ]] ||
  echo "note: $dev has MTU $(cat "/sys/class/net/$dev/mtu"), CAN FD checks will fail"

# (a) A classic frame sent with cansend arrives at candump with its exact ID and data.
check_classic() {
  local st=0 got
  start_candump "$work/a" -n 1 || { report "classic frame" 1 "candump never listened"; return; }
  cansend "$dev" 123#DEADBEEF || st=1
  wait %% 2>/dev/null
  got=$(tr -s ' ' <"$work/a" | sed 's/^ //')
  [[ $st == 0 && $got == "$dev 123 [4] DE AD BE EF" ]] || st=1
  report "classic frame 123#DEADBEEF received exactly" $st "candump printed '$got'"
}

# (b) A 64-byte CAN FD frame with bit-rate switch round-trips. The kernel adds its
# CANFD_FDF flag (0x04) to frames it delivers, so only BRS and ESI are compared.
check_fd() {
  local st=0 data got flags
  data=$(pattern 64 | tr -d ' ')
  start_candump "$work/b" -L -n 1 || { report "CAN FD frame" 1 "candump never listened"; return; }
  cansend "$dev" "123##1$data" || st=1
  wait %% 2>/dev/null
  got=$(cut -d' ' -f3 <"$work/b")
  flags=${got:5:1}
  [[ $st == 0 && ${got:0:5} == "123##" && -n $flags && $(((0x$flags) & 3)) == 1 &&
     ${got:6} == "$data" ]] || st=1
  report "CAN FD frame 123##1 with 64 bytes received exactly" $st "candump -L printed '$got'"
}

# (c) ISO-TP (ISO 15765-2) segments a 600-byte payload into a first frame, flow control
# and consecutive frames between IDs 123 and 321; the receiver must get it intact.
check_isotp() {  # NAME LINK-LAYER-ARGS...
  local name=$1 st=0 base payload got
  shift
  payload=$(pattern 600)
  count_receivers
  base=$receivers
  timeout "${MJC_WAIT_CAP_S:-300}" isotprecv "$@" -s 321 -d 123 "$dev" >"$work/c" 2>&1 &
  local rx=$!
  wait_receivers $((base + 1)) || { report "$name" 1 "isotprecv never listened"; return; }
  echo "$payload" | timeout "${MJC_WAIT_CAP_S:-300}" isotpsend "$@" -s 123 -d 321 "$dev" || st=1
  wait $rx || st=1
  got=$(tr -s ' \n' ' ' <"$work/c" | sed 's/^ //; s/ $//')
  [[ $st == 0 && $got == "$payload" ]] || st=1
  report "$name" $st "received $(wc -w <<<"$got") bytes: '${got:0:60}...'"
}

# (d) `candump -L` is the log format the host tools write: "(sec.usec) iface ID#DATA",
# ID 3 hex digits (11 bit) or 8 (29 bit), DATA upper-case hex, "R" for a remote frame,
# "##F" + data for CAN FD with F the flags nibble.
check_log_format() {
  local st=0 line n=0 prev=0 ts want got bad=
  local frames=(123#DEADBEEF 1ABCDE12#0102 7FF#R 456# "123##1$(pattern 8 | tr -d ' ')")
  start_candump "$work/d" -L -n ${#frames[@]} || { report "candump -L format" 1 "candump never listened"; return; }
  for f in "${frames[@]}"; do cansend "$dev" "$f" || st=1; done
  wait %% 2>/dev/null
  while IFS= read -r line; do
    want=${frames[n]}
    # FD frames come back with the kernel's FDF flag added (see check_fd).
    [[ $want == *"##1"* ]] && want=${want/"##1"/"##5"}
    if [[ ! $line =~ ^\(([0-9]+\.[0-9]{6})\)\ $dev\ ([0-9A-F]{3}|[0-9A-F]{8})(#R|#([0-9A-F]{2})*|##[0-9A-F]([0-9A-F]{2})*)$ ]]; then
      bad="malformed line '$line'"
      break
    fi
    ts=${BASH_REMATCH[1]}
    got=${line#* "$dev" }
    [[ $got == "$want" ]] || { bad="line $n is '$got', sent '${frames[n]}'"; break; }
    [[ ${ts/./} -ge ${prev/./} ]] || { bad="timestamps go backwards at line $n"; break; }
    prev=$ts
    n=$((n + 1))
  done <"$work/d"
  [[ -z $bad && $n != "${#frames[@]}" ]] && bad="$n of ${#frames[@]} lines"
  [[ -n $bad ]] && st=1
  cp "$work/d" "$work/log"
  report "candump -L log lines are '(sec.usec) $dev ID#DATA'" $st "$bad"
}

# (e) canplayer replays such a log onto the bus unchanged: a log the host tools write
# can be fed back by the standard tool.
check_replay() {
  local st=0 sent got
  [[ -s $work/log ]] || { report "canplayer replays the log" 1 "no log from the previous check"; return; }
  start_candump "$work/e" -L -n "$(wc -l <"$work/log")" ||
    { report "canplayer replays the log" 1 "candump never listened"; return; }
  timeout "${MJC_WAIT_CAP_S:-300}" canplayer -t -I "$work/log" || st=1
  wait %% 2>/dev/null
  sent=$(cut -d' ' -f2- "$work/log")
  got=$(cut -d' ' -f2- "$work/e")
  [[ $st == 0 && $got == "$sent" ]] || st=1
  report "canplayer replays the log frame for frame" $st "replayed: $(tr '\n' ' ' <<<"$got")"
}

check_classic
check_fd
check_isotp "ISO-TP 600 bytes intact over classic frames 123/321"
check_isotp "ISO-TP 600 bytes intact over CAN FD frames 123/321" -L 72:64:0
check_log_format
check_replay

echo "$pass passed, $fail failed"
[[ $fail == 0 ]]
