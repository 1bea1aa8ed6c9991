# Sourced by the kernel-layer scripts that run a list of checks: one PASS or FAIL line
# per check, each command's output kept in $work/check.log. $work must be set first.
passed=0
failed=0

check() {  # DESCRIPTION COMMAND...: runs the command; PASS when it exits 0
  local what=$1
  shift
  if "$@" >>"$work/check.log" 2>&1; then
    echo "PASS $what (${SECONDS} s)"
    passed=$((passed + 1))
  else
    echo "FAIL $what (${SECONDS} s)"
    failed=$((failed + 1))
  fi
}

# STATUS WANT DESCRIPTION: a check that a command's exit status (STATUS, the $? it
# left) is WANT; the description is followed by the status it got.
check_exit() {
  check "$3 (exit $1)" test "$1" -eq "$2"
}

# FILE TEXT [PID]: waits until FILE holds TEXT, for output of a process still running;
# gives up at once when PID (the process that would write it) has exited without. A
# check waits for what happens, never for a time: the cap (${MJC_WAIT_CAP_S:-300} s by
# the clock, not counted in polls, whose fork a throttled VM on a loaded machine makes
# many times slower than their 50 ms) only ends the wait for something that will not
# come, and is far beyond any slow machine's pace.
wait_for() {
  local text=
  local end=$((SECONDS + ${MJC_WAIT_CAP_S:-300}))
  while ((SECONDS < end)); do
    [[ -f $1 ]] && read -r -d '' text <"$1"
    [[ $text == *"$2"* ]] && return 0
    if [[ -n ${3:-} ]] && ! kill -0 "$3" 2>/dev/null; then
      [[ -f $1 ]] && read -r -d '' text <"$1"
      [[ $text == *"$2"* ]] && return 0
      echo "no '$2' in $1, and its writer (pid $3) has exited: $text"
      return 1
    fi
    sleep 0.05
  done
  echo "no '$2' in $1 after ${MJC_WAIT_CAP_S:-300} s: $text"
  return 1
}

# STATUS ERRFILE COMMAND...: runs the command; true when it exits with STATUS and says
# why in one line on stderr (ERRFILE): the tools' refusal contract.
refuses() {
  local want=$1 err=$2 got
  shift 2
  "$@" >/dev/null 2>"$err"
  got=$?
  echo "exit $got (want $want): $(cat "$err")"
  [ "$got" -eq "$want" ] && [ "$(wc -l <"$err")" -eq 1 ]
}

# FILE...: the summary line, with the check log and the given files' tails when a
# check failed; the status is the script's exit status.
finish() {
  if [ "$failed" -ne 0 ]; then
    echo "--- details"
    tail -n 40 "$work/check.log" "$@"
  fi
  echo "$passed passed, $failed failed"
  [ "$failed" -eq 0 ]
}
