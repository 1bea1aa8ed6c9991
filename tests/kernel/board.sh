# Sourced by the kernel-layer scripts that put a simulated joint board on vcan0: which
# board. $mjc must be set first.
#
# MJC_BOARD names the board's command; unset, it is `mjc sim`. Any board command takes
# mjc sim's options (--iface, --node, --robot, --subject, --flash, --speed, --seconds)
# and signals (SIGUSR1/SIGUSR2: the joint encoder's error flag; SIGINT/SIGTERM: stop),
# and prints mjc sim's messages behind its own name ("mjc-g474: node 1 on vcan0 (...)",
# the same summary line at the end). The virtual G474 board, the image's own code on the
# chip's register models (kernel-vm run --env):
#   MJC_BOARD=build/host/host_tools/mjc-g474
# A board command runs as `"${board[@]}" OPTIONS...`; $board_name starts its messages.
if [[ -n ${MJC_BOARD:-} ]]; then
  read -r -a board <<<"$MJC_BOARD"
  board_name=${board[0]##*/}
else
  board=("$mjc" sim)
  board_name="mjc sim"
fi

# A board is on the bus once it prints "<name>: node N on vcan0": mjc sim says it once
# its first pass has sent the board's BoardInfo and heartbeat and its socket's filters
# are the running image's; the virtual board once its firmware has booted and ticks.
wait_board() {  # ERRFILE NODE
  wait_for "$1" "$board_name: node $2 on vcan0"
}
