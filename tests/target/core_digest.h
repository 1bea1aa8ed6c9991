// A digest of the core's outputs over a long deterministic input sequence. The host
// build and the Cortex-M4 build must print the same value: any difference in integer
// semantics, rounding or saturation between the two compilers and ISAs changes it.
// Each later stage of the signal chain adds its outputs here.
#pragma once

#include <cstdint>

namespace mjc::test {

// 64-bit FNV-1a over every output of `steps` rounds of core operations.
std::uint64_t CoreDigest(std::uint32_t steps);

}  // namespace mjc::test
