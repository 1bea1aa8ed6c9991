#!/usr/bin/python3
"""scripts/first-flash's option bytes, without a probe.

The bit positions come from ST's SVD (FLASH_OPTR's nSWBOOT0, nBOOT0, DBANK), parsed here
with Python's ElementTree, not from the script. Checked:
  - the dry run (--print): the option_write it would run sets nBOOT0 = 1, clears
    nSWBOOT0 and leaves every other bit (its mask is those two bits);
  - against a stand-in OpenOCD that keeps FLASH_OPTR as the chip does (a written word
    takes effect only at option_load): a factory chip ends with nSWBOOT0 = 0, nBOOT0 = 1
    and its other bits as they were; a chip with DBANK = 0 is refused before anything
    is written; a chip whose option bytes do not take is refused with a non-zero exit;
  - --check-optr on words built from the SVD's positions.

usage: first_flash_test.py SVD SCRIPT
"""
import os
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

FACTORY = 0xFFEFF8AA  # RM0440 FLASH_OPTR, the factory option bytes

FAKE_OPENOCD = r'''#!/usr/bin/python3
# A stand-in OpenOCD: FLASH_OPTR as the chip keeps it (the loaded word, and what
# option_write leaves for the next option_load), in a JSON file.
import json, os, sys
state_path = os.environ["FAKE_OPTR_STATE"]
state = json.load(open(state_path))
args = sys.argv[1:]
with open(os.environ["FAKE_OPENOCD_LOG"], "a") as log:
    log.write(" ".join(args) + "\n")
cmds = [args[i + 1] for i in range(len(args) - 1) if args[i] == "-c"]
for c in cmds:
    w = c.split()
    if w[0] == "mdw" and int(w[1], 0) == 0x40022020:
        print("0x40022020: %08x " % state["loaded"], file=sys.stderr)
    elif w[:2] == ["stm32l4x", "option_write"]:
        if int(w[3], 0) != 0x20:
            sys.exit("unexpected option register " + w[3])
        value, mask = int(w[4], 0), int(w[5], 0) if len(w) > 5 else 0xFFFFFFFF
        if not state.get("ignore_writes"):
            state["stored"] = (state["stored"] & ~mask) | (value & mask)
    elif w[:2] == ["stm32l4x", "option_load"]:
        state["loaded"] = state["stored"]
json.dump(state, open(state_path, "w"))
'''


def svd_bits(svd):
    """FLASH_OPTR's field positions from the SVD."""
    root = ET.parse(svd).getroot()
    for reg in root.iter("register"):
        if reg.findtext("name") == "FLASH_OPTR":
            return {f.findtext("name"): int(f.findtext("bitOffset"))
                    for f in reg.iter("field")}
    raise SystemExit("FLASH_OPTR not in " + svd)


failures = 0


def check(what, ok, detail=""):
    global failures
    print(("ok   " if ok else "FAIL ") + what + ((": " + detail) if detail and not ok else ""))
    failures += 0 if ok else 1


def main():
    svd, script = sys.argv[1], sys.argv[2]
    bits = svd_bits(svd)
    nswboot0, nboot0, dbank = (1 << bits["nSWBOOT0"], 1 << bits["nBOOT0"],
                               1 << bits["DBANK"])
    check("SVD positions read", (bits["nSWBOOT0"], bits["nBOOT0"], bits["DBANK"]) == (26, 27, 22))

    # The dry run.
    out = subprocess.run([script, "--options-only", "--print"], capture_output=True,
                         text=True)
    check("--options-only --print exits 0", out.returncode == 0, out.stderr)
    m = re.search(r"stm32l4x\\? option_write\\? 0\\? 0x20\\? (0x[0-9A-Fa-f]+)\\? (0x[0-9A-Fa-f]+)",
                  out.stdout)
    check("the dry run has an option_write of FLASH_OPTR", m is not None, out.stdout)
    if m:
        value, mask = int(m.group(1), 16), int(m.group(2), 16)
        check("its mask is nSWBOOT0 | nBOOT0 (other bits kept)", mask == nswboot0 | nboot0,
              hex(mask))
        check("it sets nBOOT0 = 1", value & nboot0 != 0, hex(value))
        check("it sets nSWBOOT0 = 0", value & nswboot0 == 0, hex(value))
        written = (FACTORY & ~mask) | (value & mask)
        check("a factory word becomes 0xFBEFF8AA",
              written == (FACTORY & ~nswboot0) | nboot0 and written == 0xFBEFF8AA, hex(written))
    check("the dry run loads the option bytes", "option_load" in out.stdout, out.stdout)
    check("and reads FLASH_OPTR back", out.stdout.count("mdw\\ 0x40022020") >= 2, out.stdout)

    with tempfile.TemporaryDirectory() as tmp:
        fake = os.path.join(tmp, "openocd")
        with open(fake, "w") as f:
            f.write(FAKE_OPENOCD)
        os.chmod(fake, 0o755)
        state, log = os.path.join(tmp, "state.json"), os.path.join(tmp, "log")

        def run(initial, ignore_writes=False):
            with open(state, "w") as f:
                f.write('{"loaded": %d, "stored": %d, "ignore_writes": %s}' %
                        (initial, initial, "true" if ignore_writes else "false"))
            open(log, "w").close()
            env = dict(os.environ, OPENOCD=fake, FAKE_OPTR_STATE=state, FAKE_OPENOCD_LOG=log)
            r = subprocess.run([script, "--options-only"], capture_output=True, text=True,
                               env=env)
            import json
            return r, json.load(open(state)), open(log).read()

        r, s, _ = run(FACTORY)
        check("a factory chip: exit 0", r.returncode == 0, r.stderr)
        check("  loaded word = factory with nSWBOOT0 = 0, nBOOT0 = 1",
              s["loaded"] == (FACTORY & ~nswboot0) | nboot0, hex(s["loaded"]))

        other = FACTORY ^ (1 << bits["SRAM_PE"])  # SRAM parity on: a user's choice
        r, s, _ = run(other)
        check("other bits kept (SRAM_PE as the chip had it)",
              r.returncode == 0 and s["loaded"] == (other & ~nswboot0) | nboot0,
              hex(s["loaded"]))

        r, s, calls = run(FACTORY & ~dbank)
        check("DBANK = 0: refused (non-zero exit)", r.returncode != 0, r.stdout)
        check("  saying why", "DBANK = 0" in r.stderr, r.stderr)
        check("  before writing anything", "option_write" not in calls, calls)

        r, s, _ = run(FACTORY, ignore_writes=True)
        check("option bytes that do not take: refused (non-zero exit)", r.returncode != 0,
              r.stdout)
        check("  saying so", "did not take" in r.stderr and "nSWBOOT0 = 1" in r.stderr,
              r.stderr)

    for word, good in [((FACTORY & ~nswboot0) | nboot0, True), (FACTORY, False),
                       (FACTORY & ~nswboot0 & ~nboot0, False),
                       ((FACTORY & ~nswboot0 & ~dbank) | nboot0, False)]:
        r = subprocess.run([script, "--check-optr", "0x%08X" % word], capture_output=True,
                           text=True)
        check("--check-optr 0x%08X: %s" % (word, "accepted" if good else "refused"),
              (r.returncode == 0) == good, r.stdout + r.stderr)
    r = subprocess.run([script, "--check-optr", "0xZZ"], capture_output=True, text=True)
    check("--check-optr 0xZZ: a clear error, exit 2",
          r.returncode == 2 and "not a 32-bit hex value" in r.stderr, r.stderr)

    print("%d failed" % failures)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
