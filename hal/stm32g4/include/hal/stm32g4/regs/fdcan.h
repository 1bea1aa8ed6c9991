// FDCAN1 (RM0440 §44.4, "FDCAN registers"), the clock divider shared by the three
// FDCANs (FDCAN_CONFIG, §44.4: CKDIV) and the message RAM (§44.3.3, fixed layout on
// this chip).
//
// SVD quirk: ST's SVD describes the register block once, as peripheral "FDCAN" at
// 0x4000_A400 (which is the message RAM, SRAMCAN), with FDCAN1..3 derived from it; CKDIV
// appears there at +0x100, i.e. 0x4000_6500 for FDCAN1 — the FDCAN_CONFIG block. The
// check matches FDCAN_CONFIG.CKDIV by that absolute address.
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::fdcan {

inline constexpr FieldDef kDbtpFields[] = {
    {"DSJW", 0, 4},    // each of these four is written as value − 1
    {"DTSEG2", 4, 4},  //
    {"DTSEG1", 8, 5},  //
    {"DBRP", 16, 5},   //
    {"TDC", 23, 1},    // transmitter delay compensation on
};
inline constexpr FieldDef kCccrFields[] = {
    {"INIT", 0, 1},  {"CCE", 1, 1},   {"ASM", 2, 1},  {"CSA", 3, 1},   {"CSR", 4, 1},
    {"MON", 5, 1},   {"DAR", 6, 1},   {"TEST", 7, 1}, {"FDOE", 8, 1},  {"BRSE", 9, 1},
    {"PXHD", 12, 1}, {"EFBI", 13, 1}, {"TXP", 14, 1}, {"NISO", 15, 1},
};
inline constexpr FieldDef kNbtpFields[] = {
    {"NTSEG2", 0, 7},  // value − 1
    {"NTSEG1", 8, 8},  // value − 1
    {"NBRP", 16, 9},   // value − 1
    {"NSJW", 25, 7},   // value − 1
};
inline constexpr FieldDef kEcrFields[] = {
    {"TEC", 0, 8},   // transmit error counter
    {"REC", 8, 7},   // receive error counter
    {"RP", 15, 1},   // REC reached the error-passive level (128)
    {"CEL", 16, 8},  // CAN error logging (cleared on read)
};
inline constexpr FieldDef kPsrFields[] = {
    {"LEC", 0, 3},    // last error code (7 = no change since the last read)
    {"ACT", 3, 2},    // 00 synchronising, 01 idle, 10 receiver, 11 transmitter
    {"EP", 5, 1},     // error passive
    {"EW", 6, 1},     // warning (a counter ≥ 96)
    {"BO", 7, 1},     // bus-off
    {"DLEC", 8, 3},   // last error code in a data phase
    {"TDCV", 16, 7},  // measured transmitter delay, mtq
};
inline constexpr FieldDef kTdcrFields[] = {
    {"TDCF", 0, 7},  // filter window length, mtq
    {"TDCO", 8, 7},  // offset of the secondary sample point, mtq
};
inline constexpr FieldDef kIrFields[] = {
    {"RF0N", 0, 1},  // new message in RX FIFO 0
    {"RF0L", 2, 1},  // RX FIFO 0 message lost
    {"BO", 19, 1},   // bus-off status changed
};
inline constexpr FieldDef kIeFields[] = {
    {"RF0NE", 0, 1},
    {"RF0LE", 2, 1},
    {"BOE", 19, 1},
};
inline constexpr FieldDef kIlsFields[] = {
    // Interrupt groups to line 1 (1) or line 0 (0), RM0440 §44.4, FDCAN_ILS.
    {"RXFIFO0", 0, 1},  // RF0N, RF0F, RF0L
    // Protocol errors: ARA, PED, PEA, WDI, BO, EW. EP (error passive) is not in this
    // group but in BERR (bit 5) with ELO, as ST's HAL lists the groups.
    {"PERR", 6, 1},
};
inline constexpr FieldDef kIleFields[] = {{"EINT0", 0, 1}, {"EINT1", 1, 1}};
inline constexpr FieldDef kRxgfcFields[] = {
    {"RRFE", 0, 1},  // reject remote frames, extended
    {"RRFS", 1, 1},  // reject remote frames, standard
    {"ANFE", 2, 2},  // non-matching extended frames: 10/11 reject
    {"ANFS", 4, 2},  // non-matching standard frames: 10/11 reject
    {"LSS", 16, 5},  // standard filter elements in use, 0..28
    {"LSE", 24, 4},  // extended filter elements in use, 0..8
};
inline constexpr FieldDef kRxf0sFields[] = {
    {"F0FL", 0, 4},   // fill level
    {"F0GI", 8, 2},   // get index
    {"F0PI", 16, 2},  // put index
    {"F0F", 24, 1},   // full
    {"RF0L", 25, 1},  // message lost
};
inline constexpr FieldDef kRxf0aFields[] = {{"F0AI", 0, 3}};
inline constexpr FieldDef kTxbcFields[] = {{"TFQM", 24, 1}};  // 0: TX FIFO
inline constexpr FieldDef kTxfqsFields[] = {
    {"TFFL", 0, 3},    // free elements
    {"TFGI", 8, 2},    // get index
    {"TFQPI", 16, 2},  // put index
    {"TFQF", 21, 1},   // full
};
inline constexpr FieldDef kTxbarFields[] = {{"AR", 0, 3}};

inline constexpr RegisterDef kRegisters[] = {
    {"DBTP", 0x0C, kDbtpFields},   {"CCCR", 0x18, kCccrFields},
    {"NBTP", 0x1C, kNbtpFields},   {"ECR", 0x40, kEcrFields},
    {"PSR", 0x44, kPsrFields},     {"TDCR", 0x48, kTdcrFields},
    {"IR", 0x50, kIrFields},       {"IE", 0x54, kIeFields},
    {"ILS", 0x58, kIlsFields},     {"ILE", 0x5C, kIleFields},
    {"RXGFC", 0x80, kRxgfcFields}, {"RXF0S", 0x90, kRxf0sFields},
    {"RXF0A", 0x94, kRxf0aFields}, {"TXBC", 0xC0, kTxbcFields},
    {"TXFQS", 0xC4, kTxfqsFields}, {"TXBAR", 0xCC, kTxbarFields},
};

inline constexpr BlockDef kBlock{"FDCAN1", 0x40006400u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kDbtp = OffsetOf(kBlock, "DBTP");
inline constexpr std::uint32_t kCccr = OffsetOf(kBlock, "CCCR");
inline constexpr std::uint32_t kNbtp = OffsetOf(kBlock, "NBTP");
inline constexpr std::uint32_t kEcr = OffsetOf(kBlock, "ECR");
inline constexpr std::uint32_t kPsr = OffsetOf(kBlock, "PSR");
inline constexpr std::uint32_t kTdcr = OffsetOf(kBlock, "TDCR");
inline constexpr std::uint32_t kIr = OffsetOf(kBlock, "IR");
inline constexpr std::uint32_t kIe = OffsetOf(kBlock, "IE");
inline constexpr std::uint32_t kIls = OffsetOf(kBlock, "ILS");
inline constexpr std::uint32_t kIle = OffsetOf(kBlock, "ILE");
inline constexpr std::uint32_t kRxgfc = OffsetOf(kBlock, "RXGFC");
inline constexpr std::uint32_t kRxf0s = OffsetOf(kBlock, "RXF0S");
inline constexpr std::uint32_t kRxf0a = OffsetOf(kBlock, "RXF0A");
inline constexpr std::uint32_t kTxbc = OffsetOf(kBlock, "TXBC");
inline constexpr std::uint32_t kTxfqs = OffsetOf(kBlock, "TXFQS");
inline constexpr std::uint32_t kTxbar = OffsetOf(kBlock, "TXBAR");

namespace dbtp {
inline constexpr Field kDsjw = FieldOf(kBlock, "DBTP", "DSJW");
inline constexpr Field kDtseg2 = FieldOf(kBlock, "DBTP", "DTSEG2");
inline constexpr Field kDtseg1 = FieldOf(kBlock, "DBTP", "DTSEG1");
inline constexpr Field kDbrp = FieldOf(kBlock, "DBTP", "DBRP");
inline constexpr Field kTdc = FieldOf(kBlock, "DBTP", "TDC");
}  // namespace dbtp
namespace cccr {
inline constexpr Field kInit = FieldOf(kBlock, "CCCR", "INIT");
inline constexpr Field kCce = FieldOf(kBlock, "CCCR", "CCE");
inline constexpr Field kCsa = FieldOf(kBlock, "CCCR", "CSA");
inline constexpr Field kCsr = FieldOf(kBlock, "CCCR", "CSR");
inline constexpr Field kDar = FieldOf(kBlock, "CCCR", "DAR");
inline constexpr Field kFdoe = FieldOf(kBlock, "CCCR", "FDOE");
inline constexpr Field kBrse = FieldOf(kBlock, "CCCR", "BRSE");
inline constexpr Field kPxhd = FieldOf(kBlock, "CCCR", "PXHD");
}  // namespace cccr
namespace nbtp {
inline constexpr Field kNtseg2 = FieldOf(kBlock, "NBTP", "NTSEG2");
inline constexpr Field kNtseg1 = FieldOf(kBlock, "NBTP", "NTSEG1");
inline constexpr Field kNbrp = FieldOf(kBlock, "NBTP", "NBRP");
inline constexpr Field kNsjw = FieldOf(kBlock, "NBTP", "NSJW");
}  // namespace nbtp
namespace ecr {
inline constexpr Field kTec = FieldOf(kBlock, "ECR", "TEC");
inline constexpr Field kRec = FieldOf(kBlock, "ECR", "REC");
}  // namespace ecr
namespace psr {
inline constexpr Field kLec = FieldOf(kBlock, "PSR", "LEC");
inline constexpr Field kAct = FieldOf(kBlock, "PSR", "ACT");
inline constexpr Field kEp = FieldOf(kBlock, "PSR", "EP");
inline constexpr Field kEw = FieldOf(kBlock, "PSR", "EW");
inline constexpr Field kBo = FieldOf(kBlock, "PSR", "BO");
inline constexpr Field kDlec = FieldOf(kBlock, "PSR", "DLEC");
}  // namespace psr
namespace tdcr {
inline constexpr Field kTdcf = FieldOf(kBlock, "TDCR", "TDCF");
inline constexpr Field kTdco = FieldOf(kBlock, "TDCR", "TDCO");
}  // namespace tdcr
namespace ir {
inline constexpr Field kRf0n = FieldOf(kBlock, "IR", "RF0N");
inline constexpr Field kRf0l = FieldOf(kBlock, "IR", "RF0L");
inline constexpr Field kBo = FieldOf(kBlock, "IR", "BO");
}  // namespace ir
namespace ie {
inline constexpr Field kRf0ne = FieldOf(kBlock, "IE", "RF0NE");
inline constexpr Field kRf0le = FieldOf(kBlock, "IE", "RF0LE");
inline constexpr Field kBoe = FieldOf(kBlock, "IE", "BOE");
}  // namespace ie
namespace ils {
inline constexpr Field kRxfifo0 = FieldOf(kBlock, "ILS", "RXFIFO0");
inline constexpr Field kPerr = FieldOf(kBlock, "ILS", "PERR");
}  // namespace ils
namespace ile {
inline constexpr Field kEint0 = FieldOf(kBlock, "ILE", "EINT0");
inline constexpr Field kEint1 = FieldOf(kBlock, "ILE", "EINT1");
}  // namespace ile
namespace rxgfc {
inline constexpr Field kRrfe = FieldOf(kBlock, "RXGFC", "RRFE");
inline constexpr Field kRrfs = FieldOf(kBlock, "RXGFC", "RRFS");
inline constexpr Field kAnfe = FieldOf(kBlock, "RXGFC", "ANFE");
inline constexpr Field kAnfs = FieldOf(kBlock, "RXGFC", "ANFS");
inline constexpr Field kLss = FieldOf(kBlock, "RXGFC", "LSS");
inline constexpr Field kLse = FieldOf(kBlock, "RXGFC", "LSE");
}  // namespace rxgfc
namespace rxf0s {
inline constexpr Field kF0fl = FieldOf(kBlock, "RXF0S", "F0FL");
inline constexpr Field kF0gi = FieldOf(kBlock, "RXF0S", "F0GI");
inline constexpr Field kRf0l = FieldOf(kBlock, "RXF0S", "RF0L");
}  // namespace rxf0s
namespace rxf0a {
inline constexpr Field kF0ai = FieldOf(kBlock, "RXF0A", "F0AI");
}  // namespace rxf0a
namespace txbc {
inline constexpr Field kTfqm = FieldOf(kBlock, "TXBC", "TFQM");
}  // namespace txbc
namespace txfqs {
inline constexpr Field kTffl = FieldOf(kBlock, "TXFQS", "TFFL");
inline constexpr Field kTfqpi = FieldOf(kBlock, "TXFQS", "TFQPI");
inline constexpr Field kTfqf = FieldOf(kBlock, "TXFQS", "TFQF");
}  // namespace txfqs
namespace txbar {
inline constexpr Field kAr = FieldOf(kBlock, "TXBAR", "AR");
}  // namespace txbar

// FDCAN_CONFIG: the kernel clock divider common to FDCAN1..3; writable only while
// FDCAN1 is in configuration (CCCR.INIT = CCE = 1).
inline constexpr FieldDef kCkdivFields[] = {{"PDIV", 0, 4}};  // 0000 /1, n /2n
inline constexpr RegisterDef kConfigRegisters[] = {{"CKDIV", 0x00, kCkdivFields}};
inline constexpr BlockDef kConfigBlock{"FDCAN_CONFIG", 0x40006500u, kConfigRegisters};
static_assert(WellFormed(kConfigBlock));
inline constexpr Address kConfigBase = kConfigBlock.base;
inline constexpr std::uint32_t kCkdiv = OffsetOf(kConfigBlock, "CKDIV");
namespace ckdiv {
inline constexpr Field kPdiv = FieldOf(kConfigBlock, "CKDIV", "PDIV");
}  // namespace ckdiv

// ---- Message RAM (RM0440 §44.3.3 "Message RAM"; ST's HAL SRAMCAN_* offsets agree) ----
// Fixed on the G4: each FDCAN instance owns 212 words from SRAMCAN_BASE + n × 0x350;
// only the filter list lengths are programmable (RXGFC.LSS/LSE). 32-bit accesses only.
namespace ram {
inline constexpr Address kFdcan1 = 0x4000A400u;
inline constexpr std::uint32_t kInstanceBytes = 0x350;
inline constexpr std::uint32_t kStdFilters = 0x000;   // 28 × 1 word
inline constexpr std::uint32_t kExtFilters = 0x070;   // 8 × 2 words
inline constexpr std::uint32_t kRxFifo0 = 0x0B0;      // 3 × 18 words
inline constexpr std::uint32_t kRxFifo1 = 0x188;      // 3 × 18 words
inline constexpr std::uint32_t kTxEventFifo = 0x260;  // 3 × 2 words
inline constexpr std::uint32_t kTxBuffers = 0x278;    // 3 × 18 words
inline constexpr std::uint32_t kStdFilterCount = 28;
inline constexpr std::uint32_t kExtFilterCount = 8;
inline constexpr std::uint32_t kFifoElements = 3;
inline constexpr std::uint32_t kElementBytes = 72;  // 2 header words + 64 data bytes
static_assert(kExtFilters == kStdFilters + kStdFilterCount * 4);
static_assert(kRxFifo0 == kExtFilters + kExtFilterCount * 8);
static_assert(kRxFifo1 == kRxFifo0 + kFifoElements * kElementBytes);
static_assert(kTxEventFifo == kRxFifo1 + kFifoElements * kElementBytes);
static_assert(kTxBuffers == kTxEventFifo + kFifoElements * 8);
static_assert(kInstanceBytes == kTxBuffers + kFifoElements * kElementBytes);

// Element layouts (RM0440 §44.3.3, "Rx FIFO element", "Tx buffer element", "Standard
// message ID filter element"). These are words in RAM, not registers: the SVD does not
// describe them.
// Word 0 of RX and TX elements.
inline constexpr std::uint32_t kXtd = 1u << 30;
inline constexpr std::uint32_t kRtr = 1u << 29;
inline constexpr unsigned kStdIdShift = 18;  // an 11-bit identifier sits in ID[28:18]
inline constexpr std::uint32_t kStdIdMask = 0x7FFu;
// Word 1.
inline constexpr std::uint32_t kFdf = 1u << 21;  // FD format
inline constexpr std::uint32_t kBrs = 1u << 20;  // bit-rate switch
inline constexpr unsigned kDlcShift = 16;        // DLC[19:16]
inline constexpr std::uint32_t kEfc = 1u << 23;  // TX: store a TX event
// Standard filter element: SFT[31:30], SFEC[29:27], SFID1[26:16], SFID2[10:0].
inline constexpr unsigned kSftShift = 30;
inline constexpr std::uint32_t kSftClassic = 2;  // SFID1 = id, SFID2 = mask
inline constexpr unsigned kSfecShift = 27;
inline constexpr std::uint32_t kSfecFifo0 = 1;  // store in RX FIFO 0
inline constexpr unsigned kSfid1Shift = 16;
}  // namespace ram

}  // namespace mjc::stm32g4::fdcan
