#include "core_kernels.h"

namespace mjc::bench {

Power TorqueTimesVelocity(Torque torque, AngularVelocity velocity) {
  return Mul<Power>(torque, velocity);
}

Torque SpringTorque(Stiffness k, Angle cable_side, Angle joint) {
  return Mul<Torque>(k, cable_side - joint);
}

Ratio AngleRatio(Angle a, Angle b) { return Divide<Ratio>(a, b); }

void MatVec3(const Matrix3& a, const Vector3& x, Vector3& y) {
  y = a.lazyProduct(x).cast<Angle>();
}

}  // namespace mjc::bench
