#include "core_digest.h"

#include <Eigen/Core>

#include "mjc/core/fixed_eigen.h"
#include "mjc/core/quantities.h"
#include "mjc/core/wrapping.h"
#include "vector_test.h"

namespace mjc::test {
namespace {

class Fnv1a {
 public:
  template <class T>
  void Add(T value) {
    auto bits = static_cast<std::uint64_t>(value);
    for (unsigned i = 0; i < sizeof(T); ++i) {
      hash_ = (hash_ ^ (bits & 0xFFu)) * 0x100000001B3ull;
      bits >>= 8;
    }
  }
  std::uint64_t value() const { return hash_; }

 private:
  std::uint64_t hash_ = 0xCBF29CE484222325ull;
};

}  // namespace

std::uint64_t CoreDigest(std::uint32_t steps) {
  vt::Rng rng(0x4D4A43);  // "MJC"
  Fnv1a h;
  Eigen::Matrix<Coefficient, 3, 3> a;
  Eigen::Matrix<Angle, 3, 1> x = Eigen::Matrix<Angle, 3, 1>::Zero();
  std::uint16_t counter = 0;
  std::int64_t extended = 0;
  for (std::uint32_t i = 0; i < steps; ++i) {
    // Shift by a random amount so magnitudes span the whole range, edges included.
    const auto shift = [&rng] { return static_cast<int>(rng.Next() % 32u); };
    const auto tq = Torque::FromRaw(rng.NextI32() >> shift());
    const auto w = AngularVelocity::FromRaw(rng.NextI32() >> shift());
    const auto k = Stiffness::FromRaw(rng.NextI32() >> shift());
    const auto th = Angle::FromRaw(rng.NextI32() >> shift());
    const auto th2 = Angle::FromRaw(rng.NextI32() >> shift());
    const auto d = Duty::FromRaw(rng.NextI16());

    h.Add(Mul<Power>(tq, w).raw());
    h.Add(Mul<Torque>(k, th - th2).raw());
    h.Add((th + th2).raw());
    h.Add((th - th2).raw());
    h.Add((-th).raw());
    h.Add(Abs(th2).raw());
    h.Add(FixedCast<Fixed<Radian, 10>>(th).raw());
    h.Add(FixedCast<Fixed<Radian, 28>>(th).raw());
    h.Add(Divide<Ratio>(th, th2).raw());
    h.Add(Mul<Duty>(d, d).raw());
    h.Add((tq * static_cast<int>(rng.NextI16())).raw());

    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) a(r, c) = Coefficient::FromRaw(rng.NextI32() >> 2);
    }
    x(static_cast<Eigen::Index>(i % 3u)) = th;
    x = a.lazyProduct(x).cast<Angle>();
    for (int r = 0; r < 3; ++r) h.Add(x(r).raw());

    counter = WrappingAdd(counter, static_cast<std::uint16_t>(rng.Next() & 0x7FFFu));
    extended += WrappingDelta(counter, static_cast<std::uint16_t>(extended & 0xFFFF));
    h.Add(extended);
  }
  return h.value();
}

}  // namespace mjc::test
