#include "mjc/g474model/dbgmcu.h"

namespace mjc::g474model {

RegisterTable<Dbgmcu> Dbgmcu::Registers() {
  using R = Register<Dbgmcu>;
  // The writable bits are the SVD's fields of each register (DBGMCU block).
  static constexpr R kTable[] = {
      R::Fixed(0x00, kDevId),  // IDCODE: DEV_ID 11:0, REV_ID 31:16 (not modelled: 0)
      R::ReadWrite(0x04, &Dbgmcu::cr_, 0x000000E7u),  // DBG_SLEEP/STOP/STANDBY, TRACE
      // TIM2..7 (5:0), RTC (10), WWDG (11), IWDG (12), I2C1/2 (21, 22), I2C3 (30),
      // LPTIM1 (31).
      R::ReadWrite(0x08, &Dbgmcu::apb1fzr1_, 0xC0601C3Fu),
      R::ReadWrite(0x0C, &Dbgmcu::apb1fzr2_, 0x00000002u),  // I2C4 (1)
      // TIM1 (11), TIM8 (13), TIM15/16/17 (18:16), TIM20 (20), HRTIM (29:26).
      R::ReadWrite(0x10, &Dbgmcu::apb2fzr_, 0x3C172800u),
  };
  return kTable;
}

bool Dbgmcu::Read(const Access& a, std::uint32_t* value) {
  return ReadTableRegister(Registers(), *this, a.offset, value);
}

bool Dbgmcu::Write(const Access& a) { return WriteTableRegister(Registers(), *this, a); }

}  // namespace mjc::g474model
