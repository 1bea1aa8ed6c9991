// The STM32G474 tick I/O's register blocks placed in RAM, for the Cortex-M4 benchmark
// images on QEMU's mps2-an386 (it has no STM32 peripherals): Stm32g4JointIo takes its
// blocks as a template argument, so instantiated with these it is the board's driver,
// compiled the same way; only the addresses in its loads and stores differ.
#pragma once

#include <cstdint>

#include "hal/stm32g4/joint_io.h"

namespace mjc::bench {

// 3 MB into the 4 MB RAM: far above an image's data and below its stack.
inline constexpr stm32g4::Address kRegs = 0x20300000u;
inline constexpr stm32g4::JointIoBlocks kRamBlocks{
    .bridge_timer = kRegs + 0x0000,
    .encoder_timer = kRegs + 0x0400,
    .joint_spi = kRegs + 0x0800,
    .joint_cs = {kRegs + 0x0C00, 4},
    .bridge_enable = {kRegs + 0x1000, 10},
    .cycle_counter = kRegs + 0x1400,
    .bridge_low_side_min_ns = 1000,  // the joint board's (g474_joint/pins.h)
};

inline volatile std::uint32_t& Reg(stm32g4::Address a) {
  return *reinterpret_cast<volatile std::uint32_t*>(a);
}

}  // namespace mjc::bench
