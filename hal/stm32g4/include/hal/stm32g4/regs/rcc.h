// RCC: reset and clock control (RM0440 §7.4, "RCC registers"). Only what the clock
// bring-up, the peripheral enables and resets and the reset-cause report use.
#pragma once

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4::rcc {

inline constexpr FieldDef kCrFields[] = {
    {"HSION", 8, 1},   {"HSIRDY", 10, 1}, {"HSEON", 16, 1}, {"HSERDY", 17, 1},
    {"HSEBYP", 18, 1}, {"CSSON", 19, 1},  {"PLLON", 24, 1}, {"PLLRDY", 25, 1},
};
inline constexpr FieldDef kCfgrFields[] = {
    {"SW", 0, 2},      // 01 HSI16, 10 HSE, 11 PLLRCLK
    {"SWS", 2, 2},     // the switch's status, same coding
    {"HPRE", 4, 4},    // AHB: 0xxx /1, 1000 /2, ...
    {"PPRE1", 8, 3},   // APB1: 0xx /1, 100 /2, ...
    {"PPRE2", 11, 3},  // APB2
};
inline constexpr FieldDef kPllcfgrFields[] = {
    {"PLLSRC", 0, 2},   // 10 HSI16, 11 HSE
    {"PLLM", 4, 4},     // M - 1 (/1../16)
    {"PLLN", 8, 7},     // N, 8..127
    {"PLLPEN", 16, 1},  //
    {"PLLQEN", 20, 1},  //
    {"PLLQ", 21, 2},    // 00 /2, 01 /4, 10 /6, 11 /8
    {"PLLREN", 24, 1},  //
    {"PLLR", 25, 2},    // 00 /2, 01 /4, 10 /6, 11 /8
};
// Peripheral resets: a bit held at 1 keeps its peripheral in reset (the bootloader
// returns what it used to the reset state before it hands over).
inline constexpr FieldDef kAhb2rstrFields[] = {
    {"GPIOARST", 0, 1},
    {"GPIOBRST", 1, 1},
    {"GPIOCRST", 2, 1},
};
inline constexpr FieldDef kApb1rstr1Fields[] = {
    {"FDCANRST", 25, 1},
};
inline constexpr FieldDef kAhb2enrFields[] = {
    {"GPIOAEN", 0, 1}, {"GPIOBEN", 1, 1}, {"GPIOCEN", 2, 1}, {"GPIODEN", 3, 1},
    {"GPIOEEN", 4, 1}, {"GPIOFEN", 5, 1}, {"GPIOGEN", 6, 1},
};
inline constexpr FieldDef kApb1enr1Fields[] = {
    {"TIM3EN", 1, 1},
    {"FDCANEN", 25, 1},
    {"PWREN", 28, 1},
};
inline constexpr FieldDef kApb2enrFields[] = {
    {"SYSCFGEN", 0, 1},
    {"TIM1EN", 11, 1},
    {"SPI1EN", 12, 1},
};
inline constexpr FieldDef kCciprFields[] = {
    {"FDCANSEL", 24, 2},  // 00 HSE, 01 PLLQ, 10 PCLK1
};
inline constexpr FieldDef kCsrFields[] = {
    {"LSION", 0, 1},     {"LSIRDY", 1, 1},    {"RMVF", 23, 1},    {"OBLRSTF", 25, 1},
    {"PINRSTF", 26, 1},  {"BORRSTF", 27, 1},  {"SFTRSTF", 28, 1}, {"IWDGRSTF", 29, 1},
    {"WWDGRSTF", 30, 1}, {"LPWRRSTF", 31, 1},
};

inline constexpr RegisterDef kRegisters[] = {
    {"CR", 0x00, kCrFields},
    {"CFGR", 0x08, kCfgrFields},
    {"PLLCFGR", 0x0C, kPllcfgrFields},
    {"AHB2RSTR", 0x2C, kAhb2rstrFields},
    {"APB1RSTR1", 0x38, kApb1rstr1Fields},
    {"AHB2ENR", 0x4C, kAhb2enrFields},
    {"APB1ENR1", 0x58, kApb1enr1Fields},
    {"APB2ENR", 0x60, kApb2enrFields},
    {"CCIPR", 0x88, kCciprFields},
    {"CSR", 0x94, kCsrFields},
};

inline constexpr BlockDef kBlock{"RCC", 0x40021000u, kRegisters};
static_assert(WellFormed(kBlock));
inline constexpr Address kBase = kBlock.base;

inline constexpr std::uint32_t kCr = OffsetOf(kBlock, "CR");
inline constexpr std::uint32_t kCfgr = OffsetOf(kBlock, "CFGR");
inline constexpr std::uint32_t kPllcfgr = OffsetOf(kBlock, "PLLCFGR");
inline constexpr std::uint32_t kAhb2rstr = OffsetOf(kBlock, "AHB2RSTR");
inline constexpr std::uint32_t kApb1rstr1 = OffsetOf(kBlock, "APB1RSTR1");
inline constexpr std::uint32_t kAhb2enr = OffsetOf(kBlock, "AHB2ENR");
inline constexpr std::uint32_t kApb1enr1 = OffsetOf(kBlock, "APB1ENR1");
inline constexpr std::uint32_t kApb2enr = OffsetOf(kBlock, "APB2ENR");
inline constexpr std::uint32_t kCcipr = OffsetOf(kBlock, "CCIPR");
inline constexpr std::uint32_t kCsr = OffsetOf(kBlock, "CSR");

namespace cr {
inline constexpr Field kHsion = FieldOf(kBlock, "CR", "HSION");
inline constexpr Field kHsirdy = FieldOf(kBlock, "CR", "HSIRDY");
inline constexpr Field kHseon = FieldOf(kBlock, "CR", "HSEON");
inline constexpr Field kHserdy = FieldOf(kBlock, "CR", "HSERDY");
inline constexpr Field kHsebyp = FieldOf(kBlock, "CR", "HSEBYP");
inline constexpr Field kCsson = FieldOf(kBlock, "CR", "CSSON");
inline constexpr Field kPllon = FieldOf(kBlock, "CR", "PLLON");
inline constexpr Field kPllrdy = FieldOf(kBlock, "CR", "PLLRDY");
}  // namespace cr
namespace cfgr {
inline constexpr Field kSw = FieldOf(kBlock, "CFGR", "SW");
inline constexpr Field kSws = FieldOf(kBlock, "CFGR", "SWS");
inline constexpr Field kHpre = FieldOf(kBlock, "CFGR", "HPRE");
inline constexpr Field kPpre1 = FieldOf(kBlock, "CFGR", "PPRE1");
inline constexpr Field kPpre2 = FieldOf(kBlock, "CFGR", "PPRE2");
}  // namespace cfgr
namespace pllcfgr {
inline constexpr Field kPllsrc = FieldOf(kBlock, "PLLCFGR", "PLLSRC");
inline constexpr Field kPllm = FieldOf(kBlock, "PLLCFGR", "PLLM");
inline constexpr Field kPlln = FieldOf(kBlock, "PLLCFGR", "PLLN");
inline constexpr Field kPllqen = FieldOf(kBlock, "PLLCFGR", "PLLQEN");
inline constexpr Field kPllq = FieldOf(kBlock, "PLLCFGR", "PLLQ");
inline constexpr Field kPllren = FieldOf(kBlock, "PLLCFGR", "PLLREN");
inline constexpr Field kPllr = FieldOf(kBlock, "PLLCFGR", "PLLR");
}  // namespace pllcfgr
namespace ahb2rstr {
inline constexpr Field kGpioarst = FieldOf(kBlock, "AHB2RSTR", "GPIOARST");
inline constexpr Field kGpiobrst = FieldOf(kBlock, "AHB2RSTR", "GPIOBRST");
inline constexpr Field kGpiocrst = FieldOf(kBlock, "AHB2RSTR", "GPIOCRST");
}  // namespace ahb2rstr
namespace apb1rstr1 {
inline constexpr Field kFdcanrst = FieldOf(kBlock, "APB1RSTR1", "FDCANRST");
}  // namespace apb1rstr1
namespace ahb2enr {
inline constexpr Field kGpioaen = FieldOf(kBlock, "AHB2ENR", "GPIOAEN");
inline constexpr Field kGpioben = FieldOf(kBlock, "AHB2ENR", "GPIOBEN");
inline constexpr Field kGpiocen = FieldOf(kBlock, "AHB2ENR", "GPIOCEN");
// GPIOxEN of port index 0 (A) .. 6 (G), in table order.
inline constexpr Field kGpioen[] = {
    FieldAt(kBlock, "AHB2ENR", 0), FieldAt(kBlock, "AHB2ENR", 1),
    FieldAt(kBlock, "AHB2ENR", 2), FieldAt(kBlock, "AHB2ENR", 3),
    FieldAt(kBlock, "AHB2ENR", 4), FieldAt(kBlock, "AHB2ENR", 5),
    FieldAt(kBlock, "AHB2ENR", 6),
};
}  // namespace ahb2enr
namespace apb1enr1 {
inline constexpr Field kTim3en = FieldOf(kBlock, "APB1ENR1", "TIM3EN");
inline constexpr Field kFdcanen = FieldOf(kBlock, "APB1ENR1", "FDCANEN");
inline constexpr Field kPwren = FieldOf(kBlock, "APB1ENR1", "PWREN");
}  // namespace apb1enr1
namespace apb2enr {
inline constexpr Field kSyscfgen = FieldOf(kBlock, "APB2ENR", "SYSCFGEN");
inline constexpr Field kTim1en = FieldOf(kBlock, "APB2ENR", "TIM1EN");
inline constexpr Field kSpi1en = FieldOf(kBlock, "APB2ENR", "SPI1EN");
}  // namespace apb2enr
namespace ccipr {
inline constexpr Field kFdcansel = FieldOf(kBlock, "CCIPR", "FDCANSEL");
}  // namespace ccipr
namespace csr {
inline constexpr Field kLsion = FieldOf(kBlock, "CSR", "LSION");
inline constexpr Field kLsirdy = FieldOf(kBlock, "CSR", "LSIRDY");
inline constexpr Field kRmvf = FieldOf(kBlock, "CSR", "RMVF");
inline constexpr Field kOblrstf = FieldOf(kBlock, "CSR", "OBLRSTF");
inline constexpr Field kPinrstf = FieldOf(kBlock, "CSR", "PINRSTF");
inline constexpr Field kBorrstf = FieldOf(kBlock, "CSR", "BORRSTF");
inline constexpr Field kSftrstf = FieldOf(kBlock, "CSR", "SFTRSTF");
inline constexpr Field kIwdgrstf = FieldOf(kBlock, "CSR", "IWDGRSTF");
inline constexpr Field kWwdgrstf = FieldOf(kBlock, "CSR", "WWDGRSTF");
inline constexpr Field kLpwrrstf = FieldOf(kBlock, "CSR", "LPWRRSTF");
}  // namespace csr

}  // namespace mjc::stm32g4::rcc
