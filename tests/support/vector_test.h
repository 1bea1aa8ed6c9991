// Test vectors that run unchanged on the host (driven by GoogleTest) and on the
// Cortex-M4 test image under QEMU (driven by a semihosting main).
//
// Written by hand because GoogleTest needs a hosted OS (threads, file system, death
// tests, iostreams) and does not build for a bare-metal newlib target; the vectors must
// run on both so their outputs can be compared. This is only a registry and a few
// checks: on the host every case becomes a GoogleTest test (vector_test_gtest.cc).
//
//   MJC_VECTOR_TEST(FixedAdd, SaturatesAtMax) {
//     VT_EXPECT_EQ(sum.raw(), Q::Max().raw());
//   }
#pragma once

#include <cstdint>
#include <cstdio>

namespace mjc::vt {

class Context;
using Body = void (*)(Context&);

struct Case {
  const char* suite;
  const char* name;
  const char* file;
  int line;
  Body body;
  Case* next;
};

// Cases in registration order (static constructors; no heap).
Case* FirstCase();
struct Registrar {
  explicit Registrar(Case* c);
};

// Where failures go: GoogleTest on the host, semihosting stdout on the target.
using FailureSink = void (*)(const char* file, int line, const char* message);

class Context {
 public:
  explicit Context(FailureSink sink) : sink_(sink) {}

  int failures() const { return failures_; }

  void Fail(const char* file, int line, const char* message) {
    ++failures_;
    sink_(file, line, message);
  }

  void ExpectTrue(bool ok, const char* file, int line, const char* expr) {
    if (!ok) Fail(file, line, expr);
  }

  template <class A, class B>
  void ExpectEq(const A& a, const B& b, const char* file, int line, const char* ea,
                const char* eb) {
    if (a == b) return;
    char text[256];
    std::snprintf(text, sizeof text, "expected %s == %s, got %lld vs %lld", ea, eb,
                  static_cast<long long>(a), static_cast<long long>(b));
    Fail(file, line, text);
  }

  template <class A, class B>
  void ExpectLe(const A& a, const B& b, const char* file, int line, const char* ea,
                const char* eb) {
    if (a <= b) return;
    char text[256];
    std::snprintf(text, sizeof text, "expected %s <= %s, got %.17g vs %.17g", ea, eb,
                  static_cast<double>(a), static_cast<double>(b));
    Fail(file, line, text);
  }

  void ExpectNear(double a, double b, double tolerance, const char* file, int line,
                  const char* ea, const char* eb) {
    const double d = a > b ? a - b : b - a;
    if (d <= tolerance) return;
    char text[256];
    std::snprintf(text, sizeof text, "expected |%s - %s| <= %.3g, got %.17g vs %.17g", ea,
                  eb, tolerance, a, b);
    Fail(file, line, text);
  }

 private:
  FailureSink sink_;
  int failures_ = 0;
};

// Deterministic generator for test inputs (xorshift64*): the same sequence on every
// platform, seeded with a constant by each test.
class Rng {
 public:
  explicit constexpr Rng(std::uint64_t seed) : s_(seed ? seed : 0x9E3779B97F4A7C15ull) {}
  constexpr std::uint64_t Next() {
    s_ ^= s_ >> 12;
    s_ ^= s_ << 25;
    s_ ^= s_ >> 27;
    return s_ * 0x2545F4914F6CDD1Dull;
  }
  constexpr std::int32_t NextI32() { return static_cast<std::int32_t>(Next() >> 32); }
  constexpr std::int16_t NextI16() { return static_cast<std::int16_t>(Next() >> 48); }
  constexpr std::int64_t NextI64() { return static_cast<std::int64_t>(Next()); }

 private:
  std::uint64_t s_;
};

}  // namespace mjc::vt

#define MJC_VT_CONCAT2(a, b) a##b
#define MJC_VT_CONCAT(a, b) MJC_VT_CONCAT2(a, b)

#define MJC_VECTOR_TEST(suite, name)                                        \
  static void MjcVt_##suite##_##name(::mjc::vt::Context& vt_context);       \
  static ::mjc::vt::Case mjc_vt_case_##suite##_##name{                      \
      #suite, #name, __FILE__, __LINE__, &MjcVt_##suite##_##name, nullptr}; \
  static const ::mjc::vt::Registrar mjc_vt_registrar_##suite##_##name{      \
      &mjc_vt_case_##suite##_##name};                                       \
  static void MjcVt_##suite##_##name([[maybe_unused]] ::mjc::vt::Context& vt_context)

#define VT_EXPECT_TRUE(cond) vt_context.ExpectTrue((cond), __FILE__, __LINE__, #cond)
#define VT_EXPECT_EQ(a, b) vt_context.ExpectEq((a), (b), __FILE__, __LINE__, #a, #b)
#define VT_EXPECT_LE(a, b) vt_context.ExpectLe((a), (b), __FILE__, __LINE__, #a, #b)
#define VT_EXPECT_NEAR(a, b, tol) \
  vt_context.ExpectNear((a), (b), (tol), __FILE__, __LINE__, #a, #b)
