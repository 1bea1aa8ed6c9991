// Every register block the drivers use, in one list: what the SVD check prints and
// compares (tests/unit/hal/stm32g4/svd_dump.cc). A table added to regs/ is added here.
#pragma once

#include "hal/stm32g4/regs/cortex_m4.h"
#include "hal/stm32g4/regs/dbgmcu.h"
#include "hal/stm32g4/regs/fdcan.h"
#include "hal/stm32g4/regs/flash.h"
#include "hal/stm32g4/regs/gpio.h"
#include "hal/stm32g4/regs/irq.h"
#include "hal/stm32g4/regs/iwdg.h"
#include "hal/stm32g4/regs/pwr.h"
#include "hal/stm32g4/regs/rcc.h"
#include "hal/stm32g4/regs/register_table.h"
#include "hal/stm32g4/regs/spi.h"
#include "hal/stm32g4/regs/tim1.h"
#include "hal/stm32g4/regs/tim3.h"

namespace mjc::stm32g4 {

inline constexpr const BlockDef* kAllBlocks[] = {
    &rcc::kBlock,      &pwr::kBlock,      &flash::kBlock,       &gpio::kBlocks[0],
    &gpio::kBlocks[1], &gpio::kBlocks[2], &gpio::kBlocks[3],    &gpio::kBlocks[4],
    &gpio::kBlocks[5], &gpio::kBlocks[6], &tim1::kBlock,        &tim3::kBlock,
    &spi1::kBlock,     &fdcan::kBlock,    &fdcan::kConfigBlock, &iwdg::kBlock,
    &nvic::kBlock,     &scb::kBlock,      &dwt::kBlock,         &dcb::kBlock,
    &dbgmcu::kBlock,   &mpu::kBlock,
};

}  // namespace mjc::stm32g4
