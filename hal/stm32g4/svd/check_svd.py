#!/usr/bin/python3
"""Checks our STM32G474 register tables against ST's SVD.

Usage: check_svd.py SVD DUMP
       check_svd.py SVD --run PROGRAM   (PROGRAM prints the dump on stdout)

DUMP is what tests/unit/hal/stm32g4/svd_dump prints from the constexpr tables in
hal/stm32g4/include/hal/stm32g4/regs/, one item a line:

    block <name> <base> <svd|core>
    register <block> <register> <offset>
    field <block> <register> <field> <position> <width>
    irq <name> <number>
    vector <position> <irq name, or - for the default handler>
    cpu nvicPrioBits <n>

Every item is compared with the vendor's description, parsed here independently with
the standard library's ElementTree (derivedFrom resolved). Each mismatch is printed on
its own line naming peripheral, register and field, ours against the vendor's, and the
exit status is 1 if there is any. Rules:
  * a register's name matches the SVD's with or without the SVD's "<PERIPHERAL>_"
    prefix (ST writes RCC_CR, TIM1_CR1, FDCAN_CCCR but GPIO MODER, SPI CR1);
  * a field is looked up in every SVD register at the same offset, so a timer's CCMRx
    matches either of its two views (output compare / input capture);
  * a block the SVD does not name (FDCAN_CONFIG) is matched register by register at its
    absolute address in any SVD peripheral;
  * blocks marked core (NVIC, SCB, DWT, CoreDebug) are the ARMv7-M architecture's, which
    the SVD does not describe: they are listed as not checked;
  * every interrupt of the SVD must be in our table, and every vector position must
    hold the interrupt the SVD numbers there (position = 16 + IRQn).
"""

import subprocess
import sys
import xml.etree.ElementTree as ET


def number(text):
    text = text.strip().lower()
    if text.startswith("0x"):
        return int(text, 16)
    if text.startswith("#"):
        return int(text[1:], 2)
    return int(text, 0)


def field_bits(f):
    if f.find("bitOffset") is not None:
        return number(f.findtext("bitOffset")), number(f.findtext("bitWidth"))
    if f.find("lsb") is not None:
        lsb, msb = number(f.findtext("lsb")), number(f.findtext("msb"))
        return lsb, msb - lsb + 1
    msb, lsb = f.findtext("bitRange").strip("[]").split(":")
    return number(lsb), number(msb) - number(lsb) + 1


class Peripheral:
    def __init__(self, name, base, prefixes, registers):
        self.name = name
        self.base = base
        self.prefixes = prefixes
        # [(svd name, offset, {field: (position, width)})]
        self.registers = registers

    def keys(self, svd_name):
        keys = {svd_name}
        for p in self.prefixes:
            if p and svd_name.startswith(p + "_"):
                keys.add(svd_name[len(p) + 1:])
        return keys

    def find(self, name):
        for reg in self.registers:
            if name in self.keys(reg[0]):
                return reg
        return None

    def fields_at(self, offset):
        merged = {}
        for _, off, fields in self.registers:
            if off == offset:
                for k, v in fields.items():
                    merged.setdefault(k, v)
        return merged


def load_svd(path):
    root = ET.parse(path).getroot()
    elements = {p.findtext("name"): p for p in root.iter("peripheral")}

    def registers_of(p):
        regs = p.find("registers")
        if regs is None and p.get("derivedFrom"):
            return registers_of(elements[p.get("derivedFrom")])
        out = []
        for r in regs.iter("register") if regs is not None else []:
            fields = {}
            for f in r.iter("field"):
                fields[f.findtext("name")] = field_bits(f)
            out.append((r.findtext("name"), number(r.findtext("addressOffset")), fields))
        return out

    peripherals = {}
    interrupts = {}
    for name, p in elements.items():
        base_of = elements.get(p.get("derivedFrom"), p)
        prefixes = [name, p.get("derivedFrom"), p.findtext("groupName"),
                    base_of.findtext("groupName")]
        peripherals[name] = Peripheral(name, number(p.findtext("baseAddress")),
                                       [x for x in prefixes if x], registers_of(p))
        for irq in p.findall("interrupt"):
            interrupts[irq.findtext("name")] = number(irq.findtext("value"))
    cpu = root.find("cpu")
    prio_bits = number(cpu.findtext("nvicPrioBits")) if cpu is not None else None
    return peripherals, interrupts, prio_bits


def main(argv):
    if len(argv) == 4 and argv[2] == "--run":
        text = subprocess.run([argv[3]], check=True, capture_output=True,
                              encoding="ascii").stdout
    elif len(argv) == 3:
        with open(argv[2], encoding="ascii") as f:
            text = f.read()
    else:
        sys.stderr.write(__doc__)
        return 2
    peripherals, interrupts, prio_bits = load_svd(argv[1])
    lines = [line.split() for line in text.splitlines() if line.strip()]

    errors = []
    counts = {"blocks": 0, "registers": 0, "fields": 0, "irqs": 0, "vectors": 0}
    unchecked = []
    blocks = {}  # our block -> (base, source)
    current = {}  # (block, register) -> (svd peripheral, svd register, offset)

    def resolve_register(block, reg, offset):
        base, _ = blocks[block]
        p = peripherals.get(block)
        if p is not None:
            svd_reg = p.find(reg)
            if svd_reg is None:
                errors.append(f"{block}.{reg}: register not in the SVD's {block}")
                return None
            if svd_reg[1] != offset:
                errors.append(f"{block}.{reg}: offset ours 0x{offset:03X} "
                              f"vendor 0x{svd_reg[1]:03X} ({svd_reg[0]})")
            return (p, offset)
        # By absolute address, in any peripheral of the SVD.
        address = base + offset
        for q in peripherals.values():
            svd_reg = q.find(reg)
            if svd_reg is not None and q.base + svd_reg[1] == address:
                return (q, svd_reg[1])
        errors.append(f"{block}.{reg}: no register {reg} at 0x{address:08X} in the SVD")
        return None

    vectors = {}
    for item in lines:
        kind = item[0]
        if kind == "block":
            name, base, source = item[1], number(item[2]), item[3]
            blocks[name] = (base, source)
            if source == "core":
                unchecked.append(name)
                continue
            counts["blocks"] += 1
            p = peripherals.get(name)
            if p is None:
                continue  # matched register by register
            if p.base != base:
                errors.append(f"{name}: base ours 0x{base:08X} vendor 0x{p.base:08X}")
        elif kind == "register":
            block, reg, offset = item[1], item[2], number(item[3])
            if blocks[block][1] == "core":
                continue
            counts["registers"] += 1
            current[(block, reg)] = resolve_register(block, reg, offset)
        elif kind == "field":
            block, reg, name = item[1], item[2], item[3]
            position, width = int(item[4]), int(item[5])
            if blocks[block][1] == "core":
                continue
            counts["fields"] += 1
            found = current.get((block, reg))
            if found is None:
                errors.append(f"{block}.{reg}.{name}: register not found, field unchecked")
                continue
            p, offset = found
            svd_fields = p.fields_at(offset)
            if name not in svd_fields:
                errors.append(f"{block}.{reg}.{name}: field not in the SVD "
                              f"(vendor has {', '.join(sorted(svd_fields))})")
                continue
            vpos, vwidth = svd_fields[name]
            if (vpos, vwidth) != (position, width):
                errors.append(f"{block}.{reg}.{name}: position/width ours "
                              f"{position}/{width} vendor {vpos}/{vwidth}")
        elif kind == "irq":
            name, value = item[1], int(item[2])
            counts["irqs"] += 1
            if name not in interrupts:
                errors.append(f"irq {name}: not an interrupt of the SVD")
            elif interrupts[name] != value:
                errors.append(f"irq {name}: number ours {value} vendor {interrupts[name]}")
        elif kind == "vector":
            vectors[int(item[1])] = item[2]
        elif kind == "cpu":
            if item[1] == "nvicPrioBits" and prio_bits is not None:
                if int(item[2]) != prio_bits:
                    errors.append(f"cpu nvicPrioBits: ours {item[2]} vendor {prio_bits}")
        else:
            errors.append(f"dump: unknown line {' '.join(item)}")

    ours = {item[1] for item in lines if item[0] == "irq"}
    for name, value in sorted(interrupts.items(), key=lambda kv: kv[1]):
        if name not in ours:
            errors.append(f"irq {name} ({value}): in the SVD, missing from our table")
    if vectors:
        for name, value in interrupts.items():
            if vectors.get(16 + value) != name:
                errors.append(f"vector {16 + value}: ours {vectors.get(16 + value)} "
                              f"vendor {name} (IRQ {value})")
        for position, name in sorted(vectors.items()):
            if position < 16:
                continue
            counts["vectors"] += 1
            if name != "-" and interrupts.get(name) != position - 16:
                errors.append(f"vector {position}: holds {name}, which the SVD numbers "
                              f"{interrupts.get(name)}")
        last = max(interrupts.values())
        if 16 + last not in vectors:
            errors.append(f"vector table ends before IRQ {last}")

    if counts["fields"] == 0 or counts["irqs"] == 0 or counts["vectors"] == 0:
        errors.append("the dump holds no fields, IRQs or vectors: nothing was checked")
    for e in errors:
        print("MISMATCH " + e)
    for k in ("blocks", "registers", "fields", "irqs", "vectors"):
        print(f"svd_checked_{k}: {counts[k]}")
    print("not in the SVD (ARMv7-M core, unchecked): " + " ".join(unchecked))
    print(f"mismatches: {len(errors)}")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
