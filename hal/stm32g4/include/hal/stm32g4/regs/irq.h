// The STM32G474's interrupt numbers (IRQn, the NVIC's input = vector position − 16),
// RM0440 §13.3 Table 97 "STM32G4 Series vector table". Names are the SVD's (which the
// check matches them by). Position 85 is reserved on the G474 (AES on the
// crypto parts); the last position is 101 (FMAC).
#pragma once

#include <cstdint>
#include <string_view>

#include "hal/stm32g4/regs/register_table.h"

namespace mjc::stm32g4 {

struct IrqDef {
  std::string_view name;
  std::uint8_t number;
};

inline constexpr IrqDef kIrqs[] = {
    {"WWDG", 0},
    {"PVD_PVM", 1},
    {"RTC_TAMP_CSS_LSE", 2},
    {"RTC_WKUP", 3},
    {"FLASH", 4},
    {"RCC", 5},
    {"EXTI0", 6},
    {"EXTI1", 7},
    {"EXTI2", 8},
    {"EXTI3", 9},
    {"EXTI4", 10},
    {"DMA1_CH1", 11},
    {"DMA1_CH2", 12},
    {"DMA1_CH3", 13},
    {"DMA1_CH4", 14},
    {"DMA1_CH5", 15},
    {"DMA1_CH6", 16},
    {"DMA1_CH7", 17},
    {"ADC1_2", 18},
    {"USB_HP", 19},
    {"USB_LP", 20},
    {"FDCAN1_IT0", 21},
    {"FDCAN1_IT1", 22},
    {"EXTI9_5", 23},
    {"TIM1_BRK_TIM15", 24},
    {"TIM1_UP_TIM16", 25},
    {"TIM1_TRG_COM", 26},
    {"TIM1_CC", 27},
    {"TIM2", 28},
    {"TIM3", 29},
    {"TIM4", 30},
    {"I2C1_EV", 31},
    {"I2C1_ER", 32},
    {"I2C2_EV", 33},
    {"I2C2_ER", 34},
    {"SPI1", 35},
    {"SPI2", 36},
    {"USART1", 37},
    {"USART2", 38},
    {"USART3", 39},
    {"EXTI15_10", 40},
    {"RTC_ALARM", 41},
    {"USBWakeUP", 42},
    {"TIM8_BRK", 43},
    {"TIM8_UP", 44},
    {"TIM8_TRG_COM", 45},
    {"TIM8_CC", 46},
    {"ADC3", 47},
    {"FMC", 48},
    {"LPTIM1", 49},
    {"TIM5", 50},
    {"SPI3", 51},
    {"UART4", 52},
    {"UART5", 53},
    {"TIM6_DACUNDER", 54},
    {"TIM7", 55},
    {"DMA2_CH1", 56},
    {"DMA2_CH2", 57},
    {"DMA2_CH3", 58},
    {"DMA2_CH4", 59},
    {"DMA2_CH5", 60},
    {"ADC4", 61},
    {"ADC5", 62},
    {"UCPD1", 63},
    {"COMP1_2_3", 64},
    {"COMP4_5_6", 65},
    {"COMP7", 66},
    {"HRTIM_Master_IRQn", 67},
    {"HRTIM_TIMA_IRQn", 68},
    {"HRTIM_TIMB_IRQn", 69},
    {"HRTIM_TIMC_IRQn", 70},
    {"HRTIM_TIMD_IRQn", 71},
    {"HRTIM_TIME_IRQn", 72},
    {"HRTIM_TIM_FLT_IRQn", 73},
    {"HRTIM_TIMF_IRQn", 74},
    {"CRS", 75},
    {"SAI", 76},
    {"TIM20_BRK", 77},
    {"TIM20_UP", 78},
    {"TIM20_TRG_COM", 79},
    {"TIM20_CC", 80},
    {"FPU", 81},
    {"I2C4_EV", 82},
    {"I2C4_ER", 83},
    {"SPI4", 84},
    {"FDCAN2_IT0", 86},
    {"FDCAN2_IT1", 87},
    {"FDCAN3_IT0", 88},
    {"FDCAN3_IT1", 89},
    {"RNG", 90},
    {"LPUART", 91},
    {"I2C3_EV", 92},
    {"I2C3_ER", 93},
    {"DMAMUX_OVR", 94},
    {"QUADSPI", 95},
    {"DMA1_CH8", 96},
    {"DMA2_CH6", 97},
    {"DMA2_CH7", 98},
    {"DMA2_CH8", 99},
    {"Cordic", 100},
    {"FMAC", 101},
};

// Positions 0..kIrqCount-1 exist in the NVIC; some may be reserved.
inline constexpr std::uint32_t kIrqCount = 102;

// The IRQ number of `name`; a name not in the table does not compile.
consteval std::uint8_t IrqOf(std::string_view name) {
  for (const IrqDef& irq : kIrqs) {
    if (irq.name == name) return irq.number;
  }
  regs_detail::RegisterOrFieldNotInTable();
  return 0;
}

constexpr bool IrqTableWellFormed() {
  for (std::size_t i = 0; i < std::size(kIrqs); ++i) {
    if (kIrqs[i].number >= kIrqCount) return false;
    for (std::size_t j = 0; j < i; ++j) {
      if (kIrqs[j].number == kIrqs[i].number || kIrqs[j].name == kIrqs[i].name) {
        return false;
      }
    }
  }
  return true;
}
static_assert(IrqTableWellFormed());

namespace irq {
inline constexpr std::uint8_t kFlash = IrqOf("FLASH");
inline constexpr std::uint8_t kFdcan1Line0 = IrqOf("FDCAN1_IT0");
inline constexpr std::uint8_t kFdcan1Line1 = IrqOf("FDCAN1_IT1");
inline constexpr std::uint8_t kTim1Update = IrqOf("TIM1_UP_TIM16");
inline constexpr std::uint8_t kTim1Break = IrqOf("TIM1_BRK_TIM15");
}  // namespace irq

}  // namespace mjc::stm32g4
