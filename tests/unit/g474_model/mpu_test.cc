// The Cortex-M4 MPU against the ARMv7-M ARM (B3.5: MPU_TYPE, MPU_CTRL, MPU_RNR,
// MPU_RBAR, MPU_RASR; region priority, subregions, AP encodings, PRIVDEFENA, the PPB
// never checked) on the accesses the virtual chip sees: a denied one is reported (the
// chip would take MemManage) and not performed.
#include <gtest/gtest.h>

#include "mjc/g474model/virtual_chip.h"

namespace {

using namespace mjc::g474model;

constexpr std::uint32_t kType = 0xE000ED90, kCtrl = 0xE000ED94, kRnr = 0xE000ED98,
                        kRbar = 0xE000ED9C, kRasr = 0xE000EDA0;
constexpr std::uint32_t kT1 = 0x40012C00, kT3 = 0x40000400;
constexpr std::uint32_t kEnable = 1u, kPrivdefena = 4u;

// RASR for 2^log2 bytes with access permission `ap`, enabled.
std::uint32_t Rasr(unsigned log2, unsigned ap, std::uint32_t srd = 0) {
  return (ap << 24) | (srd << 8) | ((log2 - 1) << 1) | 1u;
}

std::size_t MpuReports(VirtualChip& c) {
  std::size_t n = 0;
  for (const Violation& v : c.violations().entries()) n += v.source == "MPU";
  return n;
}

TEST(G474Mpu, RegistersAsTheArchitectureDescribesThem) {
  VirtualChip c;
  EXPECT_EQ((c.Read(kType, 4) >> 8) & 0xFFu, 8u) << "DREGION: the M4's 8 regions";
  c.Write(kRnr, 3, 4);
  c.Write(kRbar, kT1, 4);
  c.Write(kRasr, Rasr(10, 0), 4);
  EXPECT_EQ(c.Read(kRbar, 4), kT1 | 3u) << "RBAR reads the selected REGION";
  EXPECT_EQ(c.Read(kRasr, 4), Rasr(10, 0));
  // VALID: the write's REGION field selects the region (and RNR follows).
  c.Write(kRbar, kT3 | 0x10u | 5u, 4);
  EXPECT_EQ(c.Read(kRnr, 4), 5u);
  c.Write(kRnr, 3, 4);
  EXPECT_EQ(c.Read(kRbar, 4), kT1 | 3u);
  c.Write(kRnr, 5, 4);
  c.Write(kRasr, Rasr(4, 3), 4);  // 16 bytes: below the 32-byte minimum
  EXPECT_EQ(MpuReports(c), 1u);
}

TEST(G474Mpu, NoAccessRegionFaultsAndTheRestOfTheMapIsUnchanged) {
  VirtualChip c;
  c.Write(0x40021060, 1u << 11, 4);  // TIM1EN
  c.Write(0x40021058, 2u, 4);        // TIM3EN
  c.Write(kT1 + 0x2C, 0x1234, 4);
  c.Write(kRnr, 0, 4);
  c.Write(kRbar, kT1, 4);
  c.Write(kRasr, Rasr(10, 0b000) | (1u << 28), 4);  // 1 KB, no access, XN
  c.Write(kCtrl, kEnable | kPrivdefena, 4);
  ASSERT_EQ(MpuReports(c), 0u);
  EXPECT_EQ(c.Read(kT1 + 0x2C, 4), 0u) << "denied: not performed";
  c.Write(kT1 + 0x2C, 0x5678, 4);
  EXPECT_EQ(MpuReports(c), 2u);
  c.Write(kT3 + 0x2C, 0x4321, 4);  // outside the region: the default map
  EXPECT_EQ(c.Read(kT3 + 0x2C, 4), 0x4321u);
  EXPECT_EQ(MpuReports(c), 2u);
  // The private peripheral bus is never checked, even inside a region.
  c.Write(kRnr, 1, 4);
  c.Write(kRbar, 0xE000E000u, 4);
  c.Write(kRasr, Rasr(12, 0), 4);
  c.Write(0xE000E100u, 1u << 25, 4);
  EXPECT_EQ(c.Read(0xE000E100u, 4) & (1u << 25), 1u << 25);
  EXPECT_EQ(MpuReports(c), 2u);
  // With the MPU off the block is reachable again and kept its value.
  c.Write(kCtrl, 0, 4);
  EXPECT_EQ(c.Read(kT1 + 0x2C, 4), 0x1234u);
}

TEST(G474Mpu, HighestRegionWinsSubregionsAndReadOnlyAndTheBackground) {
  VirtualChip c;
  c.Write(0x40021060, 1u << 11, 4);
  c.Write(0x40021058, 2u, 4);
  // Region 0: 1 KB no access over TIM1; region 2 over its first 256 B read-only.
  c.Write(kRnr, 0, 4);
  c.Write(kRbar, kT1, 4);
  c.Write(kRasr, Rasr(10, 0), 4);
  c.Write(kRnr, 2, 4);
  c.Write(kRbar, kT1, 4);
  c.Write(kRasr, Rasr(8, 0b110), 4);
  c.Write(kCtrl, kEnable | kPrivdefena, 4);
  (void)c.Read(kT1 + 0x00, 4);  // region 2: read allowed
  EXPECT_EQ(MpuReports(c), 0u);
  c.Write(kT1 + 0x2C, 1, 4);  // region 2: read-only
  EXPECT_EQ(MpuReports(c), 1u);
  (void)c.Read(kT1 + 0x100, 4);  // only region 0 holds it: no access
  EXPECT_EQ(MpuReports(c), 2u);
  // Region 0's subregion 2 (0x100 - 0x17F: eighths of its 1 KB) disabled: there the
  // default map decides (region 2 ends at 0xFF); 0x180 (subregion 3) is still region
  // 0's.
  c.Write(kRnr, 0, 4);
  c.Write(kRasr, Rasr(10, 0, 0b0000'0100), 4);
  (void)c.Read(kT1 + 0x100, 4);
  EXPECT_EQ(MpuReports(c), 2u);
  (void)c.Read(kT1 + 0x180, 4);
  EXPECT_EQ(MpuReports(c), 3u);
  // Without PRIVDEFENA an access outside every region faults (the background).
  c.Write(kCtrl, kEnable, 4);
  (void)c.Read(kT3 + 0x2C, 4);
  EXPECT_EQ(MpuReports(c), 4u);
}

}  // namespace
