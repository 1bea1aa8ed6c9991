# Sourced by the kernel-layer scripts: waiting for a listener to be ready.
#
# count_receivers counts in $receivers the receivers the CAN core has registered on
# ${dev:-vcan0}, whatever their filter list. A listener started in the background is
# ready once this count has grown: frames sent before that would be missed, and under
# TCG a process takes ~0.1 s to get there. (Pure bash: every fork costs ~50 ms under
# TCG.)
count_receivers() {
  local f line
  receivers=0
  for f in /proc/net/can/rcvlist_*; do
    while IFS= read -r line; do
      [[ $line =~ ^\ +${dev:-vcan0}\ +[0-9A-Fa-f] ]] && receivers=$((receivers + 1))
    done <"$f"
  done
}

wait_receivers() {  # COUNT: wait until at least COUNT are registered (cap as wait_for)
  local end=$((SECONDS + ${MJC_WAIT_CAP_S:-300}))
  while ((SECONDS < end)); do
    count_receivers
    ((receivers >= $1)) && return 0
    sleep 0.05
  done
  return 1
}

# Frames on their way: a sender that has exited may have frames still in the kernel
# (the CPU's input backlog, which a slowed VM works off late), neither in any socket nor
# counted as dropped. flush_bus sends a marker frame (extended id 1FFFFFFF, which no
# board uses) behind them — one CPU: first in, first out — and returns once a listener
# of its own has it, so every frame sent before the call has reached the sockets by
# then. Every socket on the bus also receives the marker. Fails (1) with the reason on
# stdout when its listener cannot listen.
bus_marker=1FFFFFFF
flush_bus() {
  local base listener err
  err=$(mktemp)
  count_receivers
  base=$receivers
  candump -n 1 "${dev:-vcan0},$bus_marker:1FFFFFFF" >/dev/null 2>"$err" &
  listener=$!
  if ! wait_receivers $((base + 1)); then
    echo "the bus marker's listener never listened: $(cat "$err")"
    kill "$listener" 2>/dev/null
    return 1
  fi
  cansend "${dev:-vcan0}" "$bus_marker#00"
  wait "$listener"
}

# Frames the kernel dropped before any socket saw them: the input backlog
# (net.core.netdev_max_backlog deep) overflows on a loaded, slowed VM;
# /proc/net/softnet_stat's second column counts those, in hex, per CPU.
backlog_dropped() {
  local total=0 d
  while read -r _ d _; do total=$((total + 16#$d)); done </proc/net/softnet_stat
  echo "$total"
}
