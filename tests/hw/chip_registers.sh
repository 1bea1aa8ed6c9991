#!/bin/bash
# The joint board's chip as a probe reads it: FLASH_OPTR, the clock source, the reset
# flags and FDCAN1's measured transmitter delay. Run by board_on_bus.sh when
# MJC_HW_PROBE=1 (an ST-Link on the board's SWD connector, Debian's openocd).
#
# usage: chip_registers.sh read FILE     reads the registers through OpenOCD into FILE
#                                        (mdw without halt: the core keeps running)
#        chip_registers.sh WHAT FILE     decodes FILE (OpenOCD's "ADDRESS: value" lines)
#                                        and checks WHAT: optr | clock | reset | tdc;
#                                        prints what it found, exit 0 when it is right
# environment: OPENOCD (default openocd), MJC_HW_OPENOCD_CFG (default
# "-f interface/stlink.cfg -f target/stm32g4x.cfg")
#
# Addresses and bit positions: RM0440 as ST's SVD gives them (tests/unit/scripts/
# chip_registers_test.py checks the decoding against the SVD's positions).
# Reading FDCAN1_PSR sets its last-error codes (LEC, DLEC) back to 7 ("no change", the
# M_CAN's rule): the image's next error-counter report may show "no change" where it
# would have shown the last error code.
set -u
readonly FLASH_OPTR=0x40022020
readonly RCC_CR=0x40021000 RCC_CFGR=0x40021008 RCC_PLLCFGR=0x4002100C RCC_CSR=0x40021094
readonly FDCAN1_PSR=0x40006444 FDCAN1_TDCR=0x40006448
# FDCAN1's kernel clock: PLLQ = 85 MHz (hal/stm32g4/include/hal/stm32g4/clock.h), CKDIV
# /1: one minimum time quantum (mtq) is 1/85 MHz = 11.76 ns.
readonly MTQ_PS=11765

what=${1:-}
file=${2:-}
if [ -z "$what" ] || [ -z "$file" ]; then
  echo "usage: chip_registers.sh read|optr|clock|reset|tdc FILE" >&2
  exit 2
fi

if [ "$what" = read ]; then
  # shellcheck disable=SC2086 # the configuration is a list of options
  exec "${OPENOCD:-openocd}" ${MJC_HW_OPENOCD_CFG:--f interface/stlink.cfg -f target/stm32g4x.cfg} \
    -c init -c "mdw $FLASH_OPTR" -c "mdw $RCC_CR" -c "mdw $RCC_CFGR" -c "mdw $RCC_PLLCFGR" \
    -c "mdw $RCC_CSR" -c "mdw $FDCAN1_PSR" -c "mdw $FDCAN1_TDCR" -c shutdown >"$file" 2>&1
fi

# ADDRESS: the word OpenOCD printed for it ("0x40022020: fbeff8aa"), as a number.
word() {
  local hex=${1#0x} line
  line=$(grep -i -m 1 -o "0x0*${hex}: *[0-9a-f]\{8\}" "$file") || {
    echo "no read of $1 in $file" >&2
    return 1
  }
  echo $((0x${line##*: }))
}
bit() { echo $((($1 >> $2) & 1)); }
field() { echo $((($1 >> $2) & ((1 << $3) - 1))); }

case $what in
  optr)
    v=$(word $FLASH_OPTR) || exit 1
    nswboot0=$(bit "$v" 26) nboot0=$(bit "$v" 27) dbank=$(bit "$v" 22)
    printf 'FLASH_OPTR 0x%08X: nSWBOOT0 %d, nBOOT0 %d, DBANK %d\n' "$v" "$nswboot0" "$nboot0" "$dbank"
    if [ "$nswboot0" -ne 0 ]; then
      echo "  BOOT0 comes from the PB8 pin: set the option bytes (scripts/first-flash --options-only)"
    fi
    [ "$nswboot0" -eq 0 ] && [ "$nboot0" -eq 1 ] && [ "$dbank" -eq 1 ]
    ;;
  clock)
    cr=$(word $RCC_CR) && cfgr=$(word $RCC_CFGR) && pll=$(word $RCC_PLLCFGR) || exit 1
    sws=$(field "$cfgr" 2 2) src=$(field "$pll" 0 2) hserdy=$(bit "$cr" 17)
    names=(? HSI16 HSE PLL)
    pllsrc=(none ? HSI16 HSE)
    echo "system clock ${names[$sws]} (RCC_CFGR.SWS $sws), PLL source ${pllsrc[$src]}" \
      "(PLLSRC $src), HSERDY $hserdy"
    [ "$sws" -eq 3 ] && [ "$src" -eq 3 ] && [ "$hserdy" -eq 1 ]
    ;;
  reset)
    csr=$(word $RCC_CSR) || exit 1
    flags=()
    n=25
    for name in OBLRSTF PINRSTF BORRSTF SFTRSTF IWDGRSTF WWDGRSTF LPWRRSTF; do
      [ "$(bit "$csr" $n)" -eq 1 ] && flags+=("$name")
      n=$((n + 1))
    done
    # The image reads and clears these flags at every start (its reset cause goes out in
    # its status): a flag here is a reset since, which the image did not start from.
    printf 'RCC_CSR 0x%08X: reset flags since the image read them: %s\n' "$csr" "${flags[*]:-none}"
    ;;
  tdc)
    psr=$(word $FDCAN1_PSR) && tdcr=$(word $FDCAN1_TDCR) || exit 1
    tdcv=$(field "$psr" 16 7) tdco=$(field "$tdcr" 8 7)
    delay=$((tdcv - tdco))
    echo "FDCAN1 TDCV $tdcv mtq = TDCO $tdco + measured delay $delay mtq" \
      "($((delay * MTQ_PS / 1000)) ns; ISO 11898-2 allows a loop delay up to 255 ns)"
    # A delay was measured (the node sent frames with a fast data phase) and did not
    # saturate the 7-bit field.
    [ "$delay" -gt 0 ] && [ "$tdcv" -lt 127 ]
    ;;
  *)
    echo "chip_registers.sh: unknown check '$what' (optr, clock, reset, tdc)" >&2
    exit 2
    ;;
esac
