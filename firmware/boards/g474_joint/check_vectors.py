#!/usr/bin/python3
"""Checks the linked image's vector table against ST's SVD.

Usage: check_vectors.py SVD ELF OBJCOPY NM HANDLER=INTERRUPT...

Reads .isr_vector from ELF (objcopy), names each entry by the symbol at its address
(nm), and checks, with the SVD's interrupt numbers (parsed with ElementTree):
  * the table has 16 + (last SVD interrupt + 1) entries;
  * each HANDLER sits at 16 + the SVD's number of its INTERRUPT, or, for a Cortex-M4
    system exception (NMI, HardFault, ...; the SVD does not list them), at the
    exception number the ARMv7-M Architecture Reference Manual (B1.5.2) gives it;
  * every other position of an SVD interrupt holds DefaultHandler;
  * position 1 is Reset_Handler, every other system exception DefaultHandler.
Prints each mismatch and exits 1 if there is any.
"""

# ARMv7-M ARM, B1.5.2 "Exception number definition": the system exceptions' numbers.
SYSTEM_EXCEPTIONS = {"NMI": 2, "HardFault": 3, "MemManage": 4, "BusFault": 5,
                     "UsageFault": 6, "SVCall": 11, "DebugMonitor": 12, "PendSV": 14,
                     "SysTick": 15}

import os
import struct
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET


def main(argv):
    svd, elf, objcopy, nm = argv[1:5]
    placed = dict(arg.split("=") for arg in argv[5:])
    root = ET.parse(svd).getroot()
    interrupts = {}
    for p in root.iter("peripheral"):
        for irq in p.findall("interrupt"):
            interrupts[irq.findtext("name")] = int(irq.findtext("value"), 0)

    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "vectors.bin")
        subprocess.run([objcopy, "-O", "binary", "-j", ".isr_vector", elf, out], check=True)
        with open(out, "rb") as f:
            data = f.read()
    words = struct.unpack("<%dI" % (len(data) // 4), data)
    symbols = {}
    for line in subprocess.run([nm, elf], check=True, capture_output=True,
                               encoding="ascii").stdout.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[1] in "tT":
            symbols.setdefault(int(parts[0], 16), parts[2])

    def name(position):
        return symbols.get(words[position] & ~1, "0x%08X" % words[position])

    errors = []
    expected_count = 16 + max(interrupts.values()) + 1
    if len(words) != expected_count:
        errors.append(f"table has {len(words)} entries, the SVD needs {expected_count}")
    if name(1) != "Reset_Handler":
        errors.append(f"position 1: {name(1)}, not Reset_Handler")
    system = {h: e for h, e in placed.items() if e in SYSTEM_EXCEPTIONS}
    for exception, position in SYSTEM_EXCEPTIONS.items():
        handler = next((h for h, e in system.items() if e == exception), "DefaultHandler")
        if name(position) != handler:
            errors.append(f"position {position} ({exception}): {name(position)}, "
                          f"not {handler}")
    for handler, irq in placed.items():
        if irq in SYSTEM_EXCEPTIONS:
            continue
        if irq not in interrupts:
            errors.append(f"{handler}: {irq} is not an interrupt of the SVD")
            continue
        position = 16 + interrupts[irq]
        if name(position) != handler:
            errors.append(f"position {position} ({irq}): {name(position)}, not {handler}")
    taken = {interrupts[irq] for irq in placed.values() if irq in interrupts}
    for irq, number in sorted(interrupts.items(), key=lambda kv: kv[1]):
        if number not in taken and 16 + number < len(words):
            if name(16 + number) != "DefaultHandler":
                errors.append(f"position {16 + number} ({irq}): {name(16 + number)}, "
                              "not DefaultHandler")
    for e in errors:
        print("MISMATCH " + e)
    print(f"vectors_checked: {len(words)}")
    print(f"mismatches: {len(errors)}")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
