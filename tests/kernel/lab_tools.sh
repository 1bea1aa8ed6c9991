#!/bin/bash
# The tools in a lab's hands (run inside the VM by scripts/kernel-vm), against simulated
# boards on vcan0: mjc list with two boards, then a third answering with node 2's id —
# detected by list and monitor, refused by the commands that address it (exit 7); the
# --json outputs read by jq; the command line's one-line errors; a trial's new output
# folder, its run.json read back by mjc report, and an --out that would overwrite an
# earlier run refused; mjc param's dump, set and restore round trip, its files refused
# whole, and a restore refused during a trial. Every wait is for an event (checks.sh);
# the boards keep real time (--speed 1) and the tools' own waits follow the boards'
# clocks.
# usage: lab_tools.sh <path of mjc>
set -u
mjc=$(realpath "$1")
work=$(mktemp -d)
. "$(dirname "$0")/checks.sh"
cd "$work" || exit 1  # the default output folders (out/…) land here

# The command line, before any board: one line each, exit 2.
check "a mistyped command: one line, exit 2" refuses 2 typo.err "$mjc" calbrate
check "  with a did-you-mean" \
  grep -qx "mjc: unknown command 'calbrate' (did you mean 'calibrate'?)" typo.err
check "a vector option's value out of range: one line, exit 2" \
  refuses 2 range.err "$mjc" trial --amplitudes 6 100
check "  naming the value and the range" \
  grep -qx "mjc trial: --amplitudes: 100 is outside 1..90° (see mjc trial --help)" range.err
build=$("$mjc" --version | sed -n 's/^mjc .* (build \([0-9a-f]\{8\}\)\(+dirty\)\{0,1\})$/\1/p')
check "mjc --version names its build (${build:-?})" test -n "$build"
echo '{"ifcae": "vcan0"}' >typo.json
check "a config file with an unknown key: one line, exit 1" \
  env MJC_CONFIG="$work/typo.json" bash -c "$(declare -f refuses); refuses 1 config.err '$mjc' list"
check "  naming it and the key it resembles" \
  grep -qx "mjc: $work/typo.json: unknown key 'ifcae' (did you mean 'iface'?)" config.err

# Two boards: node 1 (the robot alone) and node 2 (a subject's hand donned).
"$mjc" sim --iface vcan0 --node 1 2>sim1.err &
sim1=$!
"$mjc" sim --iface vcan0 --node 2 --subject subject1 2>sim2.err &
sim2=$!
check "board 1 comes up" wait_for sim1.err "mjc sim: node 1 on vcan0"
check "board 2 comes up" wait_for sim2.err "mjc sim: node 2 on vcan0"
"$mjc" list --iface vcan0 >list.out 2>list.err
check_exit $? 0 "mjc list hears both boards"
check "  node 1: application, its build, idle, uncalibrated, power-on" \
  grep -qE "^ +1  application  $build(\+dirty)? .* idle +no +power-on" list.out
check "  node 2 likewise" grep -qE "^ +2  application  $build" list.out
"$mjc" list --iface vcan0 --json >list.json 2>>list.err
check "mjc list --json: one object per node, read by jq" \
  jq -se "length == 2 and map(.node) == [1, 2] and all(.[]; .ambiguous == false and .build == \"$build\" and .image == \"application\" and .state == \"idle\" and (.instance | test(\"^[0-9a-f]{4}$\")))" list.json

# The plant's own slack (sim_host/params/default.json): node 2 calibrated, then a trial
# into the default folder, with the interface from the environment.
cat >cal.json <<'JSON'
{"c_right_deg": 1.1001, "c_left_deg": -0.8995, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}
JSON
check "node 2 takes a calibration" "$mjc" cal upload cal.json --iface vcan0 --node 2
MJC_IFACE=vcan0 "$mjc" trial --node 2 --protocol amplitude --amplitudes 15 --reps 3 \
  --frequency-hz 2 --rest-s 0.2 --subject S07 --no-figure >trial.out 2>trial.err
check_exit $? 0 "a trial on MJC_IFACE's interface completes"
dir=$(sed -n 's|^mjc trial: writing to \(out/trial/[0-9-]*T[0-9-]*Z\)/ (a new folder)$|\1|p' trial.err)
check "  into a new timestamped folder, and says so (${dir:-none})" test -d "${dir:-/nonexistent}"
check "  the progress counts repetitions from 1" grep -q "repetition 3/3 extension" trial.err
check "  no empty line on stderr" sh -c "! grep -qx '' trial.err"
check "run.json: the board, its calibration, the run and its end" \
  jq -e ".node == 2 and .iface == \"vcan0\" and .board.build == \"$build\" and (.board.instance | test(\"^[0-9a-f]{4}$\")) and .board.reset_cause == \"power-on\" and .calibration.calibrated and (.calibration.c_right_deg - 1.1001 | fabs) < 1e-4 and .robot == null and .subject == \"S07\" and .protocol == \"amplitude\" and .amplitudes_deg == [15] and .frequency_hz == 2 and .repetitions == 3 and .rest_s == 0.2 and (.started_utc | test(\"^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9]{2}:[0-9]{2}:[0-9]{2}Z$\")) and (.host | length) > 0 and (.mjc | length) > 0 and .end.outcome == \"completed\" and .end.fault == null" \
  "${dir:-.}/run.json"
check "windows.csv: a version note, repetitions from 1, the analysed flexions marked" \
  sh -c "head -n 1 '${dir:-.}/windows.csv' | grep -q '^# mjc windows.csv version 3' && grep -q '^1,15,3,flexion,2,1,' '${dir:-.}/windows.csv' && grep -q '^1,15,3,extension,3,0,' '${dir:-.}/windows.csv' && ! grep -q ',flexion,0,' '${dir:-.}/windows.csv'"
"$mjc" report "${dir:-.}" --no-figure >report.out 2>report.err
status=$?
check "mjc report reads run.json (exit $status), guessing nothing" \
  sh -c "test $status -eq 0 && ! grep -q 'guess' report.err && grep -q '^| 15° |' report.out"
check "  the tables say what ± is" grep -q "Each energy: mean ± standard error of the mean" report.out
check "  report.md names the board, the subject and the run" \
  grep -q "^Node 2 on vcan0, board $build.*, subject S07; amplitude protocol, started " "${dir:-.}/report.md"
cp "${dir:-.}/windows.csv" windows.before
check "an --out that holds a run is refused, exit 1, before the bus" \
  refuses 1 used.err "$mjc" trial --iface vcan0 --node 2 --out "${dir:-.}"
check "  saying why and what to do" grep -q "is not empty (report.md, run.json, run.mat, …): a run never overwrites another; .*--force" used.err
check "  and the earlier run is untouched" cmp windows.before "${dir:-.}/windows.csv"

# Parameters: node 1's dumped, two of them set (one between the steps of its format),
# files refused whole with nothing sent, the dump restored and read back; node 2's
# restore refused while a trial runs on it.
check "mjc param dump writes node 1's parameters" \
  "$mjc" param dump --iface vcan0 --node 1 -o params1.json
check "  this protocol, the node, its build, the board's values in the list's units" \
  jq -e ".protocol_version == 2 and .node == 1 and (.build | startswith(\"$build\")) and .params.heartbeat_hz == 10 and .params.telemetry_angles_hz == 1000 and .params.position_kp == 40 and .read_only.calibrated == 0 and .read_only.protocol_version == 2" params1.json
"$mjc" param set --iface vcan0 --node 1 telemetry_torque_hz=20 position_kp=0.1 >set.out 2>set.err
check_exit $? 0 "mjc param set writes two parameters and reads them back"
check "  saying what a value between steps will be stored as" grep -qx \
  "mjc param set: warning: position_kp: 0.1 will be stored as 0.100006103515625 (the nearest step of 1/65536)" set.err
check "  and what the board holds" grep -qx "node 1: position_kp = 0.100006103515625 1/rad" set.out
held() {  # what node 1 holds of the two: both as set
  "$mjc" param get --iface vcan0 --node 1 position_kp telemetry_torque_hz --json |
    jq -se 'length == 2 and .[0].raw == 6554 and .[0].value == 0.100006103515625 and .[1].value == 20'
}
check "mjc param get --json reads them back" held
jq '.protocol_version = 1' params1.json >v1.json
check "a dump of another protocol version is refused: one line, exit 1" \
  refuses 1 v1.err "$mjc" param restore --iface vcan0 --node 1 v1.json
check "  saying so; nothing sent" grep -q \
  "^mjc param restore: v1.json: dumped under protocol version 1, and this mjc speaks 2: .*; nothing was sent$" v1.err
jq '.params.posiion_kp = 1' params1.json >misspelt.json
check "an unknown key is refused with a did-you-mean" \
  refuses 1 misspelt.err "$mjc" param restore --iface vcan0 --node 1 misspelt.json
check "  naming it" grep -q "misspelt.json: unknown key 'params.posiion_kp' (did you mean 'params.position_kp'?); nothing was sent$" misspelt.err
jq '.params.calibration_alpha = 1' params1.json >readonly.json
check "a read-only key to write is refused" \
  refuses 1 readonly.err "$mjc" param restore --iface vcan0 --node 1 readonly.json
check "  naming it" grep -q "readonly.json: params.calibration_alpha is read-only: " readonly.err
jq '.params.heartbeat_hz = 20000' params1.json >range.json
check "a value out of range is refused" \
  refuses 1 range.err "$mjc" param restore --iface vcan0 --node 1 range.json
check "  with its range" grep -q "range.json: params.heartbeat_hz: 20000 is outside 10..1000 Hz; nothing was sent$" range.err
check "  nothing was sent: node 1 holds what was set" held
"$mjc" param restore --iface vcan0 --node 1 params1.json >restore.out 2>restore.err
check_exit $? 0 "mjc param restore brings the dump back"
check "  the two set ones changed, all read back" grep -qE \
  "^node 1: [0-9]+ parameters restored from params1.json \(2 changed, [0-9]+ already held\); read back identical$" restore.out
check "  a second dump holds every value of the first" sh -c "'$mjc' param dump --iface vcan0 --node 1 -o params1b.json >/dev/null && jq -en --slurpfile a params1.json --slurpfile b params1b.json '\$a[0].params == \$b[0].params and \$a[0].read_only == \$b[0].read_only'"
check "mjc param dump of node 2" "$mjc" param dump --iface vcan0 --node 2 -o params2.json
"$mjc" trial --iface vcan0 --node 2 --protocol amplitude --amplitudes 10 --reps 50 \
  --frequency-hz 0.5 --rest-s 0.2 --out long --no-figure >long.out 2>long.err &
long=$!
check "a long trial runs on node 2" wait_for long.err "repetition 1/50" "$long"
check "mjc param restore refuses while it runs: exit 4, one line" \
  refuses 4 busy.err "$mjc" param restore --iface vcan0 --node 2 params2.json
check "  saying why; nothing sent" grep -qx \
  "mjc param restore: node 2 is running (a trial or a stream): the board takes control parameters and protections only while idle; nothing was sent" busy.err
kill -INT "$long"
wait "$long"
check_exit $? 6 "  the trial, interrupted, stops the board"

# A third board answering with node 2's id.
"$mjc" sim --iface vcan0 --node 2 2>sim3.err &
sim3=$!
check "a second board with node id 2 comes up" wait_for sim3.err "mjc sim: node 2 on vcan0"
"$mjc" monitor --iface vcan0 --node 2 --node 1 --json --interval-ms 200 >monitor.json 2>monitor.err &
monitor=$!
# Both boards on the bus first: a board that has said it is up may not have sent a frame
# yet (on a slow machine), and no listener can tell of a board it has not heard.
check "mjc monitor --json reports node 2 ambiguous" wait_for monitor.json '"ambiguous":true'
"$mjc" list --iface vcan0 >list2.out 2>list2.err
check_exit $? 7 "mjc list: two boards behind node 2, exit 7"
check "  saying so" grep -qE "^ +2  TWO BOARDS: node 2 is answered by two boards \(instances [0-9a-f]{4} and [0-9a-f]{4}\): give each its own node id" list2.out
check "  node 1 is still listed" grep -qE "^ +1  application" list2.out
"$mjc" list --iface vcan0 --json >list2.json 2>/dev/null
check "mjc list --json marks node 2 ambiguous with both instances" \
  jq -se 'map(select(.node == 2))[0] | .ambiguous and (.instances | length) == 2' list2.json
check "a command on node 2 refuses: exit 7, one line" \
  refuses 7 download.err "$mjc" cal download --iface vcan0 --node 2
check "  naming both boards, nothing done" grep -q "^mjc cal download: node 2 is answered by two boards (.*): give each its own node id; nothing was done$" download.err
"$mjc" trial --iface vcan0 --node 2 --out amb --no-figure >amb.out 2>amb.err
check_exit $? 7 "a trial on node 2 refuses"
check "  and its run.json says why" jq -e '.end.outcome == "ambiguous" and (.end.message | test("two boards"))' amb/run.json
check "mjc monitor --json shows node 1 live" jq -se 'any(.[]; .node == 1 and .heard and .state == "idle")' monitor.json
kill -INT "$monitor"
wait "$monitor"
check_exit $? 7 "  and exits 7"
check "  every line is JSON with a UTC time" \
  jq -se 'all(.[]; .time | test("^[0-9]{4}-[0-9]{2}-[0-9]{2}T[0-9:.]+Z$"))' monitor.json

kill "$sim1" "$sim2" "$sim3" 2>/dev/null
wait "$sim1" "$sim2" "$sim3" 2>/dev/null
finish sim1.err sim2.err sim3.err
