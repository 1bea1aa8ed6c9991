#!/usr/bin/python3
"""tests/hw/chip_registers.sh's decoding, against ST's SVD.

The hardware test reads FLASH_OPTR, RCC_CR/CFGR/PLLCFGR/CSR and FDCAN1_PSR/TDCR through
OpenOCD (`mdw`) and judges them. Here OpenOCD's output is written from words built with
the SVD's addresses and bit positions (parsed with Python's ElementTree, not taken from
the script): a board as first-flash and the image leave it passes every check; each way
it can be wrong fails the check that concerns it, and only that one.

usage: chip_registers_test.py SVD SCRIPT
"""
import os
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET


def svd_map(svd):
    """{(register, field): (address, bit offset, width)} for the registers read."""
    root = ET.parse(svd).getroot()
    periph = {p.findtext("name"): p for p in root.iter("peripheral")}
    out = {}
    for block, regs in (("FLASH", ["FLASH_OPTR"]),
                        ("RCC", ["RCC_CR", "RCC_CFGR", "RCC_PLLCFGR", "RCC_CSR"]),
                        ("FDCAN1", ["FDCAN_PSR", "FDCAN_TDCR"])):
        p = periph[block]
        base = int(p.findtext("baseAddress"), 0)
        # FDCAN1 is derivedFrom FDCAN: its registers are FDCAN's at FDCAN1's base.
        src = periph[p.get("derivedFrom")] if p.get("derivedFrom") else p
        for r in src.iter("register"):
            if r.findtext("name") in regs:
                addr = base + int(r.findtext("addressOffset"), 0)
                out[r.findtext("name")] = addr
                for f in r.iter("field"):
                    out[(r.findtext("name"), f.findtext("name"))] = (
                        addr, int(f.findtext("bitOffset")), int(f.findtext("bitWidth")))
    return out


def main():
    svd, script = sys.argv[1], sys.argv[2]
    m = svd_map(svd)
    failures = 0

    def put(words, reg, field, value):
        addr, off, width = m[(reg, field)]
        mask = ((1 << width) - 1) << off
        words[addr] = (words.get(addr, 0) & ~mask) | ((value << off) & mask)

    def good():
        w = {m[r]: 0 for r in ("FLASH_OPTR", "RCC_CR", "RCC_CFGR", "RCC_PLLCFGR",
                               "RCC_CSR", "FDCAN_PSR", "FDCAN_TDCR")}
        w[m["FLASH_OPTR"]] = 0xFFEFF8AA  # RM0440 factory word
        put(w, "FLASH_OPTR", "nSWBOOT0", 0)
        put(w, "FLASH_OPTR", "nBOOT0", 1)
        put(w, "RCC_CR", "HSEON", 1)
        put(w, "RCC_CR", "HSERDY", 1)
        put(w, "RCC_CFGR", "SW", 3)
        put(w, "RCC_CFGR", "SWS", 3)
        put(w, "RCC_PLLCFGR", "PLLSRC", 3)
        put(w, "RCC_CSR", "LSION", 1)
        put(w, "FDCAN_TDCR", "TDCO", 12)
        put(w, "FDCAN_PSR", "TDCV", 12 + 14)  # 14 mtq at 85 MHz: 165 ns
        put(w, "FDCAN_PSR", "LEC", 7)
        return w

    def run(words, what):
        with tempfile.NamedTemporaryFile("w", suffix=".txt", delete=False) as f:
            f.write("Open On-Chip Debugger 0.12.0\n")
            for addr, v in words.items():
                f.write("0x%08x: %08x \n" % (addr, v))
            path = f.name
        r = subprocess.run([script, what, path], capture_output=True, text=True)
        os.unlink(path)
        return r

    def expect(label, words, verdicts):
        nonlocal failures
        for what in ("optr", "clock", "reset", "tdc"):
            r = run(words, what)
            ok = (r.returncode == 0) == verdicts.get(what, True)
            print(("ok   " if ok else "FAIL ") + "%s: %s %s (%s)" %
                  (label, what, "passes" if r.returncode == 0 else "fails",
                   (r.stdout + r.stderr).strip().replace("\n", " / ")))
            failures += 0 if ok else 1

    expect("a flashed board", good(), {})

    w = good()
    w[m["FLASH_OPTR"]] = 0xFFEFF8AA
    expect("factory option bytes", w, {"optr": False})
    w = good()
    put(w, "FLASH_OPTR", "DBANK", 0)
    expect("single bank", w, {"optr": False})
    w = good()
    put(w, "FLASH_OPTR", "nBOOT0", 0)
    expect("nBOOT0 = 0", w, {"optr": False})

    w = good()
    put(w, "RCC_CFGR", "SWS", 1)
    put(w, "RCC_CR", "HSERDY", 0)
    expect("a dead crystal (on HSI16)", w, {"clock": False})
    w = good()
    put(w, "RCC_PLLCFGR", "PLLSRC", 2)
    expect("the PLL from HSI16", w, {"clock": False})

    w = good()
    put(w, "FDCAN_PSR", "TDCV", 0)
    expect("no delay measured", w, {"tdc": False})
    w = good()
    put(w, "FDCAN_PSR", "TDCV", 127)
    expect("a saturated delay", w, {"tdc": False})
    w = good()
    put(w, "FDCAN_PSR", "TDCV", 12)  # the offset alone: nothing measured
    expect("TDCV = TDCO", w, {"tdc": False})
    r = run(good(), "tdc")
    ns = 14 * 1000 // 85  # 14 mtq of 1/85 MHz
    ok = "measured delay 14 mtq" in r.stdout and "(%d ns" % ns in r.stdout
    print(("ok   " if ok else "FAIL ") + "the delay in ns: " + r.stdout.strip())
    failures += 0 if ok else 1

    w = good()
    put(w, "RCC_CSR", "IWDGRSTF", 1)
    r = run(w, "reset")
    ok = r.returncode == 0 and "IWDGRSTF" in r.stdout
    print(("ok   " if ok else "FAIL ") + "a watchdog flag is named: " + r.stdout.strip())
    failures += 0 if ok else 1

    r = run({}, "optr")
    ok = r.returncode != 0 and "no read of" in r.stderr
    print(("ok   " if ok else "FAIL ") + "a register OpenOCD did not read fails: " +
          r.stderr.strip())
    failures += 0 if ok else 1

    print("%d failed" % failures)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
