// Eigen over fixed-point scalars: fixed-size matrices of mjc::Fixed.
//
// A product of two Fixed scalars is exact in the wide format (fixed.h), so a matrix
// product accumulates every term exactly (saturating only on a 64-bit overflow) and is
// rounded once, by the caller, with .cast<Target>() — which goes through Fixed's
// explicit rounding, saturating conversion. For example, with Q = Fixed<Unitless, 24>:
//
//   Eigen::Matrix<Q, 3, 3> a;  Eigen::Matrix<Q, 3, 1> x;
//   Eigen::Matrix<Q, 3, 1> y = a.lazyProduct(x).cast<Q>();
//
// Use lazyProduct (coefficient-based, no temporaries, no heap) for the small fixed
// sizes of the estimator and the plant. The target build defines EIGEN_NO_MALLOC,
// EIGEN_DONT_VECTORIZE and EIGEN_NO_IO on the mjc_eigen interface target.
#pragma once

#include <Eigen/Core>

#include "mjc/core/fixed.h"

namespace Eigen {

template <class U, int F, class R>
struct NumTraits<mjc::Fixed<U, F, R>> {
  using Real = mjc::Fixed<U, F, R>;
  using NonInteger = Real;
  using Nested = Real;
  using Literal = Real;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 0,
    ReadCost = 1,
    AddCost = 1,
    MulCost = 3,
  };
  static constexpr Real epsilon() { return Real::Epsilon(); }
  static constexpr Real dummy_precision() { return Real::Epsilon(); }
  static constexpr Real highest() { return Real::Max(); }
  static constexpr Real lowest() { return Real::Min(); }
  static constexpr int digits10() { return 0; }
  static constexpr int digits() { return Real::kBits - 1; }
  static constexpr Real infinity() { return Real::Max(); }
  static constexpr Real quiet_NaN() { return Real{}; }
};

// Products of two fixed scalars have their own (wide, exact) type.
template <class U1, int F1, class R1, class U2, int F2, class R2>
struct ScalarBinaryOpTraits<
    mjc::Fixed<U1, F1, R1>, mjc::Fixed<U2, F2, R2>,
    internal::scalar_product_op<mjc::Fixed<U1, F1, R1>, mjc::Fixed<U2, F2, R2>>> {
  using ReturnType = decltype(mjc::Fixed<U1, F1, R1>{} * mjc::Fixed<U2, F2, R2>{});
};

}  // namespace Eigen
