// Eigen fixed-size matrices over fixed-point scalars: a matrix-vector product sums its
// exact wide terms and rounds once, so each output is within 0.5 LSB of the
// double-precision product (unless it saturates, where it equals the bound).
#include <Eigen/Core>

#include "mjc/core/fixed_eigen.h"
#include "mjc/core/quantities.h"
#include "vector_test.h"

namespace {

using mjc::Angle;
using mjc::Coefficient;
using Matrix3 = Eigen::Matrix<Coefficient, 3, 3>;
using Vector3 = Eigen::Matrix<Angle, 3, 1>;

MJC_VECTOR_TEST(FixedEigen, MatVecWithinHalfLsbOfDouble) {
  mjc::vt::Rng rng(81);
  double worst = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Matrix3 a;
    Vector3 x;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) a(i, j) = Coefficient::FromRaw(rng.NextI32());
      x(i) = Angle::FromRaw(rng.NextI32() >> 4);  // |x| < 8 rad keeps |a x| in range
    }
    const Vector3 y = a.lazyProduct(x).cast<Angle>();
    for (int i = 0; i < 3; ++i) {
      double exact = 0;
      for (int j = 0; j < 3; ++j) exact += a(i, j).ToDouble() * x(j).ToDouble();
      double e = (y(i).ToDouble() - exact) / Angle::Epsilon().ToDouble();
      e = e < 0 ? -e : e;
      worst = e > worst ? e : worst;
    }
  }
  VT_EXPECT_LE(worst, 0.5 + 1e-6);
}

MJC_VECTOR_TEST(FixedEigen, IdentityZeroAndSums) {
  const Matrix3 eye = Matrix3::Identity();
  VT_EXPECT_TRUE(eye(0, 0) == Coefficient(1));
  VT_EXPECT_TRUE(eye(0, 1) == Coefficient{});
  Vector3 x;
  x << Angle::FromRaw(5), Angle::FromRaw(-7), Angle::Max();
  const Vector3 y = eye.lazyProduct(x).cast<Angle>();
  VT_EXPECT_TRUE(y == x);
  const Vector3 twice = x + x;  // element-wise saturating
  VT_EXPECT_TRUE(twice(2) == Angle::Max());
  VT_EXPECT_EQ(twice(1).raw(), -14);
  VT_EXPECT_TRUE(Vector3::Zero()(1) == Angle{});
}

MJC_VECTOR_TEST(FixedEigen, ProductOfSaturatingOperandsSaturates) {
  Matrix3 a = Matrix3::Constant(Coefficient::Max());
  Vector3 x = Vector3::Constant(Angle::Max());
  const Vector3 y = a.lazyProduct(x).cast<Angle>();
  VT_EXPECT_TRUE(y(0) == Angle::Max());
  x = Vector3::Constant(Angle::Min());
  const Vector3 z = a.lazyProduct(x).cast<Angle>();
  VT_EXPECT_TRUE(z(1) == Angle::Min());
}

}  // namespace
