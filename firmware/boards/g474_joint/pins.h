// The joint board's pin-out: every signal, its pin, mode and alternate function, as data
// (ConfigurePin takes each entry). STM32G474 in LQFP64 (RET6).
//
// Alternate-function numbers checked against ST's STM32G474 alternate-function table
// (DS12288, "Alternate function" tables) as carried by modm-io/modm-devices
// `devices/stm32/stm32g4-74_84.xml` @ cd25d12 (generated from ST's CubeMX pin database):
//   PA4  —                 (AF5 would be SPI1_NSS; here a plain output: the AS5047P's CS)
//   PA5  AF5 SPI1_SCK      PA6  AF5 SPI1_MISO      PA7  AF5 SPI1_MOSI
//   PA8  AF6 TIM1_CH1      PA9  AF6 TIM1_CH2
//   PB13 AF6 TIM1_CH1N     PB14 AF6 TIM1_CH2N
//   PC6  AF2 TIM3_CH1      PC7  AF2 TIM3_CH2
//   PA11 AF9 FDCAN1_RX     PA12 AF9 FDCAN1_TX
// Pins kept free on purpose: PA13/PA14 (SWD), PB3 (SWO), PB8 (BOOT0: a pulled signal
// there would select the ROM bootloader at reset with the factory option bytes; the
// board pulls it down and scripts/first-flash sets nSWBOOT0 = 0, docs/BRINGUP.md),
// PB4/PB6 (UCPD1's dead-battery pull-downs after reset), PF0/PF1 (the 24 MHz crystal,
// taken by the HSE when HSEON is set), PB12 (TIM1_BKIN, AF6: reserved for the gate
// driver's fault output as a hardware break input).
#pragma once

#include <cstdint>

#include "hal/stm32g4/gpio.h"

namespace mjc::board {

using stm32g4::OutputType;
using stm32g4::Pin;
using stm32g4::PinConfig;
using stm32g4::PinMode;
using stm32g4::Port;
using stm32g4::Pull;
using stm32g4::Speed;

inline constexpr Pin kJointCs{Port::kA, 4};
inline constexpr Pin kBridgeEnable{Port::kB, 10};
inline constexpr Pin kStatusLed{Port::kB, 11};

// The gate driver's minimum low-side on-time per PWM period (stm32g4/bridge_pwm.h).
// The firmware assumes a half-bridge driver whose high side runs from a bootstrap
// capacitor, the safe assumption until the schematic says otherwise (check the driver's
// type and its datasheet's minimum low-side on-time before the first power-up): that
// capacitor is recharged through its diode only while the leg's low side conducts, and
// it loses the high-side MOSFET's gate charge and the driver's quiescent current every
// period. 1 µs a period is the order such drivers ask for (as recalled, not taken from
// a given part's datasheet) and leaves the recharge (a few ohms into a µF-class
// capacitor) time to replace that charge at 20 kHz; it comes on top of the 253 ns dead
// time, during which neither transistor conducts. With
// CompareMargin(1000) = 107 counts the low side conducts 2 × 107 counts − 43 = 171
// counts (1.006 µs) a period at a full command, and the largest mean voltage is
// (4250 − 214) / 4250 = 94.96 % of the supply instead of 100 %. A charge-pump driver
// (100 % duty allowed) would not need it; the value then only costs those 5 %.
inline constexpr std::uint32_t kBridgeLowSideMinNs = 1000;

inline constexpr PinConfig kPins[] = {
    // H-bridge: gate driver inputs, push-pull, fast edges (the dead time is 250 ns).
    {.pin = {Port::kA, 8},
     .mode = PinMode::kAlternate,
     .alternate = 6,
     .speed = Speed::kHigh,
     .pull = Pull::kDown},  // TIM1_CH1  leg A high side
    {.pin = {Port::kB, 13},
     .mode = PinMode::kAlternate,
     .alternate = 6,
     .speed = Speed::kHigh,
     .pull = Pull::kDown},  // TIM1_CH1N leg A low side
    {.pin = {Port::kA, 9},
     .mode = PinMode::kAlternate,
     .alternate = 6,
     .speed = Speed::kHigh,
     .pull = Pull::kDown},  // TIM1_CH2  leg B high side
    {.pin = {Port::kB, 14},
     .mode = PinMode::kAlternate,
     .alternate = 6,
     .speed = Speed::kHigh,
     .pull = Pull::kDown},  // TIM1_CH2N leg B low side
    // The bridge's enable line: low (disabled) from the moment it becomes an output;
    // the board's pull-down holds it low before and after (reset, watchdog).
    {.pin = kBridgeEnable,
     .mode = PinMode::kOutput,
     .pull = Pull::kDown,
     .initial_high = false},
    // Motor encoder A/B (open-collector outputs on the encoder: pulled up).
    {.pin = {Port::kC, 6},
     .mode = PinMode::kAlternate,
     .alternate = 2,
     .pull = Pull::kUp},  // TIM3_CH1
    {.pin = {Port::kC, 7},
     .mode = PinMode::kAlternate,
     .alternate = 2,
     .pull = Pull::kUp},  // TIM3_CH2
    // Joint encoder on SPI1; CS idle high.
    {.pin = {Port::kA, 5},
     .mode = PinMode::kAlternate,
     .alternate = 5,
     .speed = Speed::kMedium},  // SPI1_SCK
    {.pin = {Port::kA, 6},
     .mode = PinMode::kAlternate,
     .alternate = 5,
     .pull = Pull::kUp},  // SPI1_MISO (the sensor tri-states it while CS is high)
    {.pin = {Port::kA, 7},
     .mode = PinMode::kAlternate,
     .alternate = 5,
     .speed = Speed::kMedium},  // SPI1_MOSI
    {.pin = kJointCs,
     .mode = PinMode::kOutput,
     .speed = Speed::kMedium,
     .initial_high = true},
    // CAN FD transceiver.
    {.pin = {Port::kA, 11},
     .mode = PinMode::kAlternate,
     .alternate = 9,
     .pull = Pull::kUp},  // FDCAN1_RX
    {.pin = {Port::kA, 12},
     .mode = PinMode::kAlternate,
     .alternate = 9,
     .speed = Speed::kHigh},  // FDCAN1_TX
    {.pin = kStatusLed, .mode = PinMode::kOutput},
};

}  // namespace mjc::board
