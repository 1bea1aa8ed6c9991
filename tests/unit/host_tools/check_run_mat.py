#!/usr/bin/python3
"""Reads the run folders run_mat_sample wrote back with scipy (scipy.io.loadmat, a
MAT-file reader we did not write) and checks run.mat against the folders' own files:
every CSV column as a field of the struct named after the file, numbers equal to the
CSV's decimal text, words as strings; each field's unit as its column's name spells it;
each JSON file's text, byte for byte. Prints what it checked and exits 1 on a mismatch.

Usage: check_run_mat.py SAMPLE_WRITER DIR
"""
import csv
import os
import subprocess
import sys

import scipy.io

# The units the tools' column names carry (mat_record.h), spelled out independently.
UNITS = {"amplitude_deg": "deg", "eta_pct": "%", "loading_J": "J", "unloading_J": "J",
         "net_J": "J", "positive_J": "J", "negative_J": "J", "peak_power_W": "W",
         "peak_torque_Nm": "N*m", "stiffness_Nm_rad": "N*m/rad",
         "damping_Nms_rad": "N*m*s/rad", "offset_Nm": "N*m", "residual_rms_Nm": "N*m",
         "motor_rad": "rad", "joint_rad": "rad"}


def rows_of(path):
    with open(path, newline="") as f:
        lines = [line for line in f if not line.startswith("#")]
    reader = csv.reader(lines)
    header = next(reader)
    return header, list(reader)


def check_folder(folder, failures):
    mat = scipy.io.loadmat(os.path.join(folder, "run.mat"), squeeze_me=False)
    checked = 0
    for name in sorted(os.listdir(folder)):
        stem, ext = os.path.splitext(name)
        path = os.path.join(folder, name)
        if ext == ".csv":
            header, rows = rows_of(path)
            if stem not in mat:
                failures.append(f"{folder}: no struct {stem}")
                continue
            record = mat[stem][0, 0]
            units = mat["units"][0, 0][stem][0, 0]
            for c, column in enumerate(header):
                got = record[column]
                want = [row[c] for row in rows]
                if got.shape != (len(rows), 1):
                    failures.append(f"{stem}.{column}: shape {got.shape}, {len(rows)} rows")
                    continue
                for i, text in enumerate(want):
                    value = got[i, 0]
                    try:
                        number = float(text)
                        ok = value.dtype.kind == "f" and value == number
                    except ValueError:
                        ok = str(value[0]) == text
                    if not ok:
                        failures.append(f"{stem}.{column} row {i + 1}: {value!r}, CSV {text!r}")
                        break
                    checked += 1
                unit = str(units[column][0])
                if unit != UNITS.get(column, "1"):
                    failures.append(f"units.{stem}.{column}: {unit!r}, want "
                                    f"{UNITS.get(column, '1')!r}")
        elif ext == ".json":
            with open(path, encoding="utf-8") as f:
                text = f.read()
            key = stem + "_json"
            if key not in mat or str(mat[key][0]) != text:
                failures.append(f"{folder}: {key} is not {name}'s text")
            checked += 1
    return checked


def main(argv):
    writer, root = argv[1:3]
    subprocess.run([writer, root], check=True)
    failures = []
    checked = 0
    for folder in ("trial", "calibrate"):
        checked += check_folder(os.path.join(root, folder), failures)
    for f in failures:
        print("MISMATCH " + f)
    print(f"run_mat_values_checked: {checked}")
    print(f"mismatches: {len(failures)}")
    return 1 if failures or checked == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
