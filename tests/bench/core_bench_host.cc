// Google Benchmark of the core kernels on the host. Names are stable: ./bench turns
// each into a "<name>_ns: <value> ns" line.
#include <benchmark/benchmark.h>

#include "core_kernels.h"

namespace {

using namespace mjc;
using namespace mjc::literals;

void FixedMul(benchmark::State& state) {
  Torque t = 0.2_Nm;
  AngularVelocity w = 0.15_rad_s;
  for (auto _ : state) {
    benchmark::DoNotOptimize(t);
    benchmark::DoNotOptimize(w);
    benchmark::DoNotOptimize(bench::TorqueTimesVelocity(t, w));
  }
}
BENCHMARK(FixedMul)->Name("fixed_mul_host");

void SpringTorque(benchmark::State& state) {
  Stiffness k = 0.63_Nm_rad;
  Angle a = 0.4_rad, b = 0.39_rad;
  for (auto _ : state) {
    benchmark::DoNotOptimize(k);
    benchmark::DoNotOptimize(a);
    benchmark::DoNotOptimize(bench::SpringTorque(k, a, b));
  }
}
BENCHMARK(SpringTorque)->Name("spring_torque_host");

void FixedDivide(benchmark::State& state) {
  Angle a = 0.4_rad, b = 1.3_rad;
  for (auto _ : state) {
    benchmark::DoNotOptimize(a);
    benchmark::DoNotOptimize(b);
    benchmark::DoNotOptimize(bench::AngleRatio(a, b));
  }
}
BENCHMARK(FixedDivide)->Name("fixed_div_host");

void MatVec3(benchmark::State& state) {
  bench::Matrix3 a = bench::Matrix3::Identity();
  a(0, 1) = Coefficient::FromDouble(0.25);
  bench::Vector3 x = bench::Vector3::Constant(0.1_rad);
  bench::Vector3 y;
  for (auto _ : state) {
    benchmark::DoNotOptimize(a.data());
    benchmark::DoNotOptimize(x.data());
    bench::MatVec3(a, x, y);
    benchmark::DoNotOptimize(y.data());
  }
}
BENCHMARK(MatVec3)->Name("eigen_matvec3_host");

}  // namespace

BENCHMARK_MAIN();
