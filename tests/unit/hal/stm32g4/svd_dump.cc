// Prints every register definition of hal/stm32g4 (blocks, registers, fields), the IRQ
// table and the vector table's layout, one item a line, for hal/stm32g4/svd/check_svd.py
// to compare with ST's SVD. The format is that script's docstring.
#include <cstdio>
#include <string_view>

#include "hal/stm32g4/regs/all_blocks.h"
#include "hal/stm32g4/vector_table.h"

namespace mjc::stm32g4 {
namespace {

void Print(std::string_view s) { std::fwrite(s.data(), 1, s.size(), stdout); }

void PrintBlock(const BlockDef& block) {
  std::printf("block ");
  Print(block.name);
  std::printf(" 0x%08X %s\n", static_cast<unsigned>(block.base),
              block.source == BlockSource::kVendorSvd ? "svd" : "core");
  for (const RegisterDef& reg : block.registers) {
    std::printf("register ");
    Print(block.name);
    std::printf(" ");
    Print(reg.name);
    std::printf(" 0x%03X\n", static_cast<unsigned>(reg.offset));
    for (const FieldDef& field : reg.fields) {
      std::printf("field ");
      Print(block.name);
      std::printf(" ");
      Print(reg.name);
      std::printf(" ");
      Print(field.name);
      std::printf(" %u %u\n", static_cast<unsigned>(field.position),
                  static_cast<unsigned>(field.width));
    }
  }
}

// The vector table as the start-up code builds it, with each IRQ's name as its handler.
constexpr auto kNamedVectors = [] {
  std::array<IrqHandler<std::string_view>, std::size(kIrqs)> named{};
  for (std::size_t i = 0; i < std::size(kIrqs); ++i) {
    named[i] = {kIrqs[i].number, kIrqs[i].name};
  }
  const SystemHandlers<std::string_view> system{
      "Reset",      "NMI",    "HardFault",    "MemManage", "BusFault",
      "UsageFault", "SVCall", "DebugMonitor", "PendSV",    "SysTick"};
  return BuildVectorTable(system, std::string_view("-"), std::string_view("-"), named);
}();

}  // namespace
}  // namespace mjc::stm32g4

int main() {
  using namespace mjc::stm32g4;
  for (const BlockDef* block : kAllBlocks) PrintBlock(*block);
  for (const IrqDef& irq : kIrqs) {
    std::printf("irq ");
    Print(irq.name);
    std::printf(" %u\n", static_cast<unsigned>(irq.number));
  }
  for (std::size_t i = 0; i < kNamedVectors.size(); ++i) {
    std::printf("vector %zu ", i + 1);
    Print(kNamedVectors[i]);
    std::printf("\n");
  }
  std::printf("cpu nvicPrioBits %u\n", kNvicPriorityBits);
  return 0;
}
