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
  local i
  for ((i = 0; i < ${MJC_WAIT_CAP_S:-300} * 20; i++)); do
    count_receivers
    ((receivers >= $1)) && return 0
    sleep 0.05
  done
  return 1
}
