// Cortex-M4 benchmark image: runs each core kernel once between two marker calls.
// scripts/cm4-instructions traces the run in QEMU and counts the instructions executed
// between mjc_bench_begin and mjc_bench_end; the "baseline" entry (an empty body)
// measures the markers' own cost, which the script subtracts. Built NO_HEAP and
// NO_DOUBLE: it is also the link-time proof that the core needs neither.
#include "core_kernels.h"
#include "semihost.h"

extern "C" {
// Not inlined and not empty to the optimiser, so their addresses bracket each run.
__attribute__((noinline)) void mjc_bench_begin() { asm volatile("" ::: "memory"); }
__attribute__((noinline)) void mjc_bench_end() { asm volatile("" ::: "memory"); }
}

namespace {

using namespace mjc;
using namespace mjc::literals;

// Inputs and outputs through volatile globals: the compiler cannot precompute a
// kernel, and loading/storing them is part of every entry including the baseline.
volatile std::int32_t g_in[4] = {(0.2_Nm).raw(), (0.15_rad_s).raw(), (0.4_rad).raw(),
                                 (0.39_rad).raw()};
volatile std::int32_t g_out = 0;
bench::Matrix3 g_matrix = bench::Matrix3::Identity();
bench::Vector3 g_x = bench::Vector3::Constant(0.1_rad);
bench::Vector3 g_y;

void Baseline() { g_out = g_in[0]; }
void FixedMul() {
  g_out = bench::TorqueTimesVelocity(Torque::FromRaw(g_in[0]),
                                     AngularVelocity::FromRaw(g_in[1]))
              .raw();
}
void SpringTorque() {
  g_out =
      bench::SpringTorque(0.63_Nm_rad, Angle::FromRaw(g_in[2]), Angle::FromRaw(g_in[3]))
          .raw();
}
void FixedDivide() {
  g_out = bench::AngleRatio(Angle::FromRaw(g_in[2]), Angle::FromRaw(g_in[3])).raw();
}
void MatVec3() {
  bench::MatVec3(g_matrix, g_x, g_y);
  g_out = g_y(0).raw();
}

struct Entry {
  const char* name;
  void (*run)();
};

// Names are stable: ./bench prints each as "<name>_cm4: <count> instructions".
constexpr Entry kEntries[] = {
    {"baseline", Baseline},          {"fixed_mul", FixedMul},
    {"spring_torque", SpringTorque}, {"fixed_div", FixedDivide},
    {"eigen_matvec3", MatVec3},
};

}  // namespace

int main() {
  for (const Entry& e : kEntries) {
    qemu::SemihostWrite("bench: ");
    qemu::SemihostWrite(e.name);
    qemu::SemihostWrite("\n");
    mjc_bench_begin();
    e.run();
    mjc_bench_end();
  }
  return 0;
}
