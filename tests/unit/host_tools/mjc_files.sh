#!/bin/sh
# mjc's files and messages without a bus (label unit): mjc report on a folder whose host
# died, and its refusals of files no run wrote (one line, exit 1, naming the line and
# field); --force before a file is replaced; a did-you-mean for a misspelt flag; an
# interface that is not CAN named as such, with no run folder left behind.
# usage: mjc_files.sh <path of mjc> <scratch folder>
set -u
mjc=$1
work=$2
rm -rf "$work"
mkdir -p "$work"
cd "$work" || exit 1
passed=0
failed=0
check() {  # DESCRIPTION COMMAND...
  what=$1
  shift
  if "$@" >>check.log 2>&1; then
    echo "PASS $what"
    passed=$((passed + 1))
  else
    echo "FAIL $what"
    failed=$((failed + 1))
  fi
}
# STATUS ERR TEXT COMMAND...: the command exits STATUS with one line on stderr holding TEXT.
refuses() {
  want=$1 err=$2 text=$3
  shift 3
  "$@" >/dev/null 2>"$err"
  got=$?
  echo "exit $got (want $want): $(cat "$err")"
  [ "$got" -eq "$want" ] && [ "$(wc -l <"$err")" -eq 1 ] && grep -qF -- "$text" "$err"
}

# A run whose host was killed after three windows: run.json says "running", its process
# (this script's pid, no mjc) is gone from the record's point of view.
mkdir dead
cat >dead/windows.csv <<'CSV'
# mjc windows.csv version 3: trial and repetition count from 1; analysed = 1 for the middle three flexions the tables use; the attachment's fit tau = k*theta + b*omega + offset per window (version 2 had no fit columns; version 1, without this line, counted repetitions from 0)
trial,amplitude_deg,repetitions,motion,repetition,analysed,eta_valid,eta_pct,loading_J,unloading_J,net_J,positive_J,negative_J,peak_power_W,peak_torque_Nm,fit_valid,stiffness_Nm_rad,damping_Nms_rad,offset_Nm,residual_rms_Nm
1,15,5,flexion,1,0,1,40,0.01,-0.006,0.004,0.011,-0.007,0.02,0.1,0,0,0,0,0
1,15,5,extension,1,0,1,35,0.008,-0.0052,0.0028,0.009,-0.006,0.02,0.1,0,0,0,0,0
1,15,5,flexion,2,1,1,41,0.01,-0.0059,0.0041,0.011,-0.007,0.02,0.1,0,0,0,0,0
CSV
cat >dead/run.json <<JSON
{"format": "mjc run 2", "command": "trial", "node": 1, "iface": "vcan0", "board": null,
 "calibration": null, "robot": null, "subject": null, "protocol": "amplitude",
 "amplitudes_deg": [15], "frequency_hz": 0.5, "repetitions": 5, "rest_s": 0.2,
 "started_utc": "2026-11-28T10:00:00Z", "host": "$(hostname)", "mjc": "test",
 "end": {"outcome": "running", "fault": null, "message": ""}, "pid": 4194304,
 "params": null}
JSON
"$mjc" report --no-figure dead >dead.out 2>dead.err
check "mjc report reads a folder whose host died (exit $?)" test -s dead/report.md
check "  saying the host stopped after 3 windows" \
  grep -q "the host stopped after 3 windows without a word" dead.err
check "  in report.md too" grep -q "the host stopped after 3 windows" dead/report.md

# Files no run wrote: refused naming the line (or key) and field.
edit() {  # NAME FILE SED: a copy of the dead run's folder with FILE edited
  rm -rf "$1"
  cp -r dead "$1"
  rm -f "$1/report.md"
  sed -i "$3" "$1/$2"
}
edit nan windows.csv '3s/,40,/,nan,/'
check "a nan is refused" refuses 1 nan.err "windows.csv: line 3, eta_pct: 'nan' is not a finite" \
  "$mjc" report --no-figure nan
edit huge windows.csv '3s/,0.011,/,1e300,/'
check "1e300 is refused" refuses 1 huge.err "line 3, positive_J: 1e300 is outside [0, 128]" \
  "$mjc" report --no-figure huge
edit twice windows.csv '5p'
check "a duplicated row is refused" refuses 1 twice.err "line 6, the flexion of repetition 2 of trial 1 again (first on line 5)" \
  "$mjc" report --no-figure twice
edit amp run.json 's/"amplitudes_deg": \[15\]/"amplitudes_deg": [20]/'
check "an amplitude contradicting run.json is refused" refuses 1 amp.err "windows.csv's trial 1 ran at 15°, but run.json says 20°" \
  "$mjc" report --no-figure amp
edit xyz run.json 's/"protocol": "amplitude"/"protocol": "xyz"/'
check "a protocol \"xyz\" is refused" refuses 1 xyz.err "field 'protocol' \"xyz\" is none of" \
  "$mjc" report --no-figure xyz
edit dup run.json 's/"node": 1,/"node": 1, "node": 2,/'
check "a key given twice is refused" refuses 1 dup.err "key 'node' appears twice" \
  "$mjc" report --no-figure dup
edit trailing run.json '$a {}'
check "data after the object is refused" refuses 1 trailing.err "not valid JSON" \
  "$mjc" report --no-figure trailing
printf '{"c_right_deg": 1.1, "c_left_deg": -0.9, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0, "c_right_deg": 5.0}\n' >cal-dup.json
check "a calibration with c_right_deg twice is refused" \
  refuses 1 cal.err "key 'c_right_deg' appears twice" "$mjc" cal show cal-dup.json
printf '{"c_right_deg": 0.0192, "c_left_deg": -0.9, "alpha": 1.0, "sea_stiffness_Nm_per_rad": 0.63, "joint_zero_count": 0}\n' >cal-rad.json
"$mjc" cal show cal-rad.json >cal-rad.out 2>cal-rad.err
check "radians in a degree field are accepted (exit $?) with a warning naming the slip" \
  grep -q "c_right_deg = 0.0192° is below two counts of the 14-bit joint encoder.*radians written in a degree field" cal-rad.err

# Nothing replaced without --force: refused before any board is asked.
echo keep >held.json
check "mjc param dump -o over a file is refused" \
  refuses 1 dump.err "held.json exists: nothing is replaced without --force" \
  "$mjc" param dump --iface mjcnosuchcan0 -o held.json
check "mjc cal download --out over a file is refused" \
  refuses 1 download.err "held.json exists: nothing is replaced without --force" \
  "$mjc" cal download --iface mjcnosuchcan0 --out held.json
check "  and the file is as it was" grep -qx keep held.json

# A misspelt flag gets a suggestion, as a misspelt command does.
check "a misspelt flag: did you mean" refuses 2 flag.err "did you mean '--node'?" \
  "$mjc" trial --nod 2

# An interface that is not CAN, named as such; the run leaves no folder.
if [ -r /sys/class/net/lo/type ]; then
  "$mjc" trial --iface lo --out lo-run --no-figure >lo.out 2>lo.err
  check "--iface lo: exit 1 (got $?)" test $? -eq 1
  check "  saying it is not a CAN interface" \
    grep -q "^mjc trial: 'lo' is not a CAN interface (it is a loopback device)" lo.err
  check "  and no run folder left" test ! -e lo-run
fi

echo "$passed passed, $failed failed"
[ "$failed" -eq 0 ] || { tail -n 40 check.log; exit 1; }
