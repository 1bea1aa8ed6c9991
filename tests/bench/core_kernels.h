// Small core workloads measured both by Google Benchmark on the host and by exact
// instruction counts on the Cortex-M4 under QEMU. Inputs come in as arguments and
// results go out as return values so neither side can constant-fold them away.
#pragma once

#include <Eigen/Core>

#include "mjc/core/fixed_eigen.h"
#include "mjc/core/quantities.h"

namespace mjc::bench {

using Matrix3 = Eigen::Matrix<Coefficient, 3, 3>;
using Vector3 = Eigen::Matrix<Angle, 3, 1>;

// P = τ·θ̇ rounded to the power format (the per-tick interface power product).
Power TorqueTimesVelocity(Torque torque, AngularVelocity velocity);
// τ = K·(θ̃ − θ) (the SEA torque).
Torque SpringTorque(Stiffness k, Angle cable_side, Angle joint);
// a / b through int64 (a software division on Cortex-M4).
Ratio AngleRatio(Angle a, Angle b);
// y = A·x for a 3×3 observer-sized matrix, exact accumulation, one rounding.
void MatVec3(const Matrix3& a, const Vector3& x, Vector3& y);

}  // namespace mjc::bench
