// The simulator's plant alone, per 100 µs tick, for ./bench (Google Benchmark): what
// the simulated board's closed loop pays for the physics, without the firmware, the
// bus or the host library (sim_tick_ns is the whole loop; scripts/sim-profile splits
// it by layer).
//
//   plant_tick_host   one tick of subject1's joint as mjc-paper integrates it (one
//                     100 µs substep), its two sensor reads with noise (the motor
//                     count and one joint frame) and the two truth figures the
//                     scenarios record each tick (interface energy and power). The
//                     motor is driven by a proportional-derivative duty on the plant's
//                     own pulley angle, computed in double here, towards the paper's
//                     25° 0.5 Hz sine: the cable crosses its slack twice a cycle, so
//                     the contacts and the sheath's friction are exercised as in a
//                     trial. The counter pulley_peak_rad shows the motion took place.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "mjc/plant/params.h"
#include "mjc/plant/plant.h"

namespace {

void PlantTick(benchmark::State& state) {
  mjc::plant::PlantParams params = mjc::plant::LoadPlantParams("subject1");
  params.integration.max_step_s = 100e-6;  // mjc-paper's substep: one a tick
  mjc::plant::Plant plant(params);
  constexpr double kTick_s = 100e-6;
  constexpr double kAmplitude_rad = 25.0 * std::numbers::pi / 180.0;
  constexpr double kOmega = 2.0 * std::numbers::pi * 0.5;
  // Gains under which the pulley reaches 94 % of the sine's amplitude on this plant
  // (pulley_peak_rad 0.41 of 0.436; duty per rad, per rad/s); the duty saturates at ±1
  // as the bridge does. The cost hardly depends on them (113–114 ns from 72 % to 96 %).
  constexpr double kP = 20.0, kD = 0.2;
  double peak = 0, sink = 0;
  for (auto _ : state) {
    const double t = plant.time();
    const double target = kAmplitude_rad * std::sin(kOmega * t);
    const double target_rate = kAmplitude_rad * kOmega * std::cos(kOmega * t);
    const mjc::plant::Plant::State& x = plant.state();
    const double angle = x(mjc::plant::Plant::Index::kMotorAngle);
    const double rate = x(mjc::plant::Plant::Index::kMotorVelocity);
    const double duty =
        std::clamp(kP * (target - angle) + kD * (target_rate - rate), -1.0, 1.0);
    plant.Step(duty, true, kTick_s);
    sink += plant.MotorCount() + plant.JointFrame() + plant.interface_energy_J() +
            plant.interface_power_W();
    peak = std::max(peak, std::fabs(angle));
  }
  benchmark::DoNotOptimize(sink);
  state.counters["pulley_peak_rad"] = peak;
}
BENCHMARK(PlantTick)->Name("plant_tick_host");

}  // namespace

BENCHMARK_MAIN();
