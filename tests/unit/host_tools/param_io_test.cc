// The parameters on the host: exact decimals of the raw fixed-point values (against
// glibc's printf, which prints a double's exact expansion), values in the list's units
// rounded to their format and checked against the list's access and range before
// anything is sent, and a dump file's checks before a restore.
#include "mjc/host/param_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace {

using namespace mjc;
using host::ParamSetting;
using protocol::ParamInfo;

const ParamInfo& Param(const char* key) {
  const ParamInfo* info = host::FindParam(key);
  EXPECT_NE(info, nullptr) << key;
  return *info;
}

// raw / 2^frac by glibc: a double holds it exactly and %.Nf prints its exact decimal
// expansion (N = frac digits suffice), trailing zeros then dropped.
std::string PrintfReference(const ParamInfo& info, std::int32_t raw) {
  char text[96];
  std::snprintf(text, sizeof text, "%.*f", info.frac_bits,
                std::ldexp(static_cast<double>(raw), -info.frac_bits));
  std::string s = text;
  if (s.find('.') != std::string::npos) {
    while (s.back() == '0') s.pop_back();
    if (s.back() == '.') s.pop_back();
  }
  return s;
}

// Raw values worth trying for `info`: its bounds, around zero, and seeded random ones
// within its range.
std::vector<std::int32_t> SomeRaws(const ParamInfo& info) {
  std::vector<std::int32_t> raws = {static_cast<std::int32_t>(info.min_raw),
                                    static_cast<std::int32_t>(info.max_raw)};
  for (const std::int32_t r : {-1, 0, 1, 3}) {
    if (r >= info.min_raw && r <= info.max_raw) raws.push_back(r);
  }
  std::mt19937_64 rng(20261124);
  std::uniform_int_distribution<std::int64_t> pick(info.min_raw, info.max_raw);
  for (int i = 0; i < 200; ++i) raws.push_back(static_cast<std::int32_t>(pick(rng)));
  return raws;
}

TEST(ParamValues, EveryRawIsWrittenAsItsExactDecimal) {
  int checked = 0;
  for (const ParamInfo& info : protocol::kParams) {
    for (const std::int32_t raw : SomeRaws(info)) {
      ASSERT_EQ(host::FormatParamValue(info, raw), PrintfReference(info, raw))
          << info.key << " raw " << raw;
      ++checked;
    }
  }
  EXPECT_GT(checked, 4000);
  // By hand: 6554 / 2^16 and -1 / 2^16.
  EXPECT_EQ(host::FormatParamValue(Param("position_kp"), 6554), "0.100006103515625");
  EXPECT_EQ(host::FormatParamValue(Param("position_kp"), -1), "-0.0000152587890625");
  EXPECT_EQ(host::FormatParamWithUnit(Param("heartbeat_hz"), 10), "10 Hz");
  EXPECT_EQ(host::FormatParamWithUnit(Param("calibrated"), 1), "1");
}

TEST(ParamValues, EveryRawComesBackFromItsValueExactly) {
  for (const ParamInfo& info : protocol::kParams) {
    if (info.access == protocol::ParamAccess::kReadOnly) continue;
    for (const std::int32_t raw : SomeRaws(info)) {
      std::string why;
      const auto s = host::CheckParamWrite(info, host::ParamValueOf(info, raw), &why);
      ASSERT_TRUE(s) << info.key << " raw " << raw << ": " << why;
      EXPECT_EQ(s->raw, raw) << info.key;
      EXPECT_TRUE(s->exact) << info.key;
      EXPECT_EQ(s->RoundingNote(), "");
    }
  }
}

TEST(ParamValues, AValueBetweenStepsIsRoundedAndSaysWhatWillBeStored) {
  std::string why;
  const auto kp = host::ParseParamAssignment("position_kp=0.1", &why);
  ASSERT_TRUE(kp) << why;
  EXPECT_EQ(kp->raw, 6554);  // 0.1·65536 = 6553.6
  EXPECT_FALSE(kp->exact);
  EXPECT_EQ(kp->RoundingNote(),
            "position_kp: 0.1 will be stored as 0.100006103515625 (the nearest step of "
            "1/65536)");
  const auto hz = host::ParseParamAssignment("heartbeat_hz=10.5", &why);
  ASSERT_TRUE(hz) << why;
  EXPECT_EQ(hz->raw, 11);  // half away from zero
  EXPECT_EQ(hz->RoundingNote(),
            "heartbeat_hz: 10.5 will be stored as 11 (it takes whole "
            "numbers)");
  const auto exact = host::ParseParamAssignment("position_kd=+.5e-1", &why);
  ASSERT_TRUE(exact) << why;
  EXPECT_EQ(exact->raw, 3277);  // 0.05·65536 = 3276.8
  const auto half = host::ParseParamAssignment("position_kd=0.5", &why);
  ASSERT_TRUE(half) << why;
  EXPECT_TRUE(half->exact);
  EXPECT_EQ(half->raw, 32768);
}

TEST(ParamValues, TheListsRangeAndAccessAreCheckedBeforeSending) {
  std::string why;
  EXPECT_FALSE(host::ParseParamAssignment("heartbeat_hz=10001", &why));
  EXPECT_EQ(why, "heartbeat_hz: 10001 is outside 10..1000 Hz");
  EXPECT_FALSE(host::ParseParamAssignment("heartbeat_hz=0", &why));
  EXPECT_EQ(why, "heartbeat_hz: 0 is outside 10..1000 Hz");
  EXPECT_FALSE(host::ParseParamAssignment("stream_timeout_ms=0", &why));
  EXPECT_EQ(why, "stream_timeout_ms: 0 is outside 1..100 ms");
  EXPECT_FALSE(host::ParseParamAssignment("host_timeout_ms=60000", &why));
  EXPECT_EQ(why, "host_timeout_ms: 60000 is outside 200..1000 ms");
  EXPECT_FALSE(host::ParseParamAssignment("position_kp=-1", &why));
  EXPECT_EQ(why, "position_kp: -1 is outside 0..400 1/rad");
  EXPECT_FALSE(host::ParseParamAssignment("position_kp=1e300", &why));
  EXPECT_EQ(why, "position_kp: 1e+300 is outside 0..400 1/rad");
  EXPECT_FALSE(host::ParseParamAssignment("torque_max=100", &why));
  EXPECT_EQ(why, "torque_max: 100 is outside 0.000000059604644775390625..5 N.m");
  EXPECT_FALSE(host::ParseParamAssignment("calibration_alpha=1", &why));
  EXPECT_EQ(why.rfind("calibration_alpha is read-only: ", 0), 0u) << why;
  EXPECT_NE(why.find("mjc cal upload"), std::string::npos) << why;
  EXPECT_FALSE(host::ParseParamAssignment("protocol_version=2", &why));
  EXPECT_EQ(why.rfind("protocol_version is read-only", 0), 0u) << why;
}

TEST(ParamValues, TheCommandLinesWordsAreJudgedWithADidYouMean) {
  std::string why;
  EXPECT_FALSE(host::ParseParamAssignment("position_kp", &why));
  EXPECT_EQ(why, "'position_kp': expected KEY=VALUE");
  EXPECT_FALSE(host::ParseParamAssignment("posiion_kp=1", &why));
  EXPECT_EQ(why, "unknown key 'posiion_kp' (did you mean 'position_kp'?)");
  for (const char* bad : {"0x10", "nan", "inf", "", "1e", ".", "1,5", "1 ", "--1"}) {
    EXPECT_FALSE(host::ParseParamAssignment(std::string("position_kp=") + bad, &why))
        << bad;
    EXPECT_EQ(why, std::string("position_kp: '") + bad + "' is not a decimal number");
  }
  for (const char* good : {"1", "5.", ".5", "-0", "1E2", "2e+1"}) {
    EXPECT_TRUE(host::ParseParamAssignment(std::string("position_kp=") + good, &why))
        << good << ": " << why;
  }
}

// --- the dump file -----------------------------------------------------------------

// A reading of every parameter: raw = a value within its range derived from its index,
// so that a value moved to another key would show.
std::vector<host::ParamReading> Readings() {
  std::vector<host::ParamReading> out;
  for (const ParamInfo* info : host::AllParams()) {
    const std::int64_t span = info->max_raw - info->min_raw;
    const auto raw =
        static_cast<std::int32_t>(info->min_raw + (span * (std::ssize(out) + 3)) / 101);
    out.push_back({info, raw});
  }
  return out;
}

nlohmann::json Dump() {
  protocol::BoardInfo info;
  info.build = 0x1958ba84;
  info.dirty = true;
  info.instance = 0x3f2a;
  return nlohmann::json::parse(
      host::ParamDumpToJson(2, info, Readings(), "2026-11-24T10:31:05Z").dump(2));
}

TEST(ParamFile, ADumpReadsBackAsTheWritesOfItsWritableParameters) {
  const nlohmann::json j = Dump();
  EXPECT_EQ(j["protocol_version"], protocol::kVersion);
  EXPECT_EQ(j["node"], 2);
  EXPECT_EQ(j["build"], "1958ba84+dirty");
  EXPECT_EQ(j["instance"], "3f2a");
  EXPECT_EQ(j["dumped_utc"], "2026-11-24T10:31:05Z");
  EXPECT_TRUE(j["read_only"]["protocol_version"].is_number_integer());  // not 1.0
  std::string why;
  const auto settings = host::ParamRestoreFromJson(j, &why);
  ASSERT_TRUE(settings) << why;
  std::size_t writable = 0;
  for (const host::ParamReading& r : Readings()) {
    if (r.info->access == protocol::ParamAccess::kReadOnly) {
      EXPECT_FALSE(j["params"].contains(r.info->key)) << r.info->key;
      EXPECT_TRUE(j["read_only"].contains(r.info->key)) << r.info->key;
      continue;
    }
    ASSERT_LT(writable, settings->size());
    const ParamSetting& s = (*settings)[writable++];
    EXPECT_EQ(s.info, r.info);  // in the list's order
    EXPECT_EQ(s.raw, r.raw) << r.info->key;
    EXPECT_TRUE(s.exact) << r.info->key;
  }
  EXPECT_EQ(writable, settings->size());
  EXPECT_GE(writable, 14u);
}

TEST(ParamFile, TheListsOrderWhateverTheFilesOrder) {
  nlohmann::json j = {{"protocol_version", protocol::kVersion},
                      {"params", {{"torque_max", 1.5}, {"heartbeat_hz", 20}}}};
  std::string why;
  const auto settings = host::ParamRestoreFromJson(j, &why);
  ASSERT_TRUE(settings) << why;
  ASSERT_EQ(settings->size(), 2u);
  EXPECT_STREQ((*settings)[0].info->key, "heartbeat_hz");
  EXPECT_STREQ((*settings)[1].info->key, "torque_max");
}

// Each edit of a good dump, and the reason the file is then refused whole.
TEST(ParamFile, AFileIsRefusedWholeWithAReason) {
  struct Case {
    const char* what;
    nlohmann::json patch;  // RFC 6902
    std::string reason;
  };
  const std::vector<Case> cases = {
      {"another protocol version",
       {{{"op", "replace"}, {"path", "/protocol_version"}, {"value", 1}}},
       "dumped under protocol version 1, and this mjc speaks 2: its parameters may mean "
       "other things (restore it with an mjc of that version)"},
      {"no protocol version",
       {{{"op", "remove"}, {"path", "/protocol_version"}}},
       "'protocol_version' missing or not a whole number (mjc param dump writes it)"},
      {"an unknown key at the top",
       {{{"op", "add"}, {"path", "/parms"}, {"value", nlohmann::json::object()}}},
       "unknown key 'parms' (did you mean 'params'?)"},
      {"an unknown parameter",
       {{{"op", "add"}, {"path", "/params/posiion_kp"}, {"value", 1}}},
       "unknown key 'params.posiion_kp' (did you mean 'params.position_kp'?)"},
      {"a read-only parameter to write",
       {{{"op", "add"}, {"path", "/params/calibration_alpha"}, {"value", 1}}},
       "params.calibration_alpha is read-only: the board reports it and takes no writes "
       "(pulley ratio r_m/r_j; a calibration is uploaded whole, with mjc cal upload)"},
      {"a value out of range",
       {{{"op", "replace"}, {"path", "/params/heartbeat_hz"}, {"value", 20000}}},
       "params.heartbeat_hz: 20000 is outside 10..1000 Hz"},
      {"a value that is not a number",
       {{{"op", "replace"}, {"path", "/params/heartbeat_hz"}, {"value", "10"}}},
       "params.heartbeat_hz must be a number, not \"10\""},
      {"a writable parameter among the read-only ones",
       {{{"op", "add"}, {"path", "/read_only/position_kp"}, {"value", 1}}},
       "read_only.position_kp is writable: its place is under params, or a restore "
       "leaves it out"},
      {"no params",
       {{{"op", "remove"}, {"path", "/params"}}},
       "'params' missing or not an object (the parameters to write, by key)"},
      {"a node outside 1..8",
       {{{"op", "replace"}, {"path", "/node"}, {"value", 9}}},
       "'node' must be a whole number in 1..8, not 9"},
  };
  for (const Case& c : cases) {
    std::string why;
    EXPECT_FALSE(host::ParamRestoreFromJson(Dump().patch(c.patch), &why)) << c.what;
    EXPECT_EQ(why, c.reason) << c.what;
  }
  std::string why;
  EXPECT_FALSE(host::ParamRestoreFromJson(nlohmann::json::array(), &why));
  EXPECT_EQ(why, "the top level must be an object");
}

TEST(ParamFile, AValueBetweenStepsIsKeptRounded) {
  nlohmann::json j = {{"protocol_version", protocol::kVersion},
                      {"params", {{"position_kp", 0.1}}}};
  std::string why;
  const auto settings = host::ParamRestoreFromJson(j, &why);
  ASSERT_TRUE(settings) << why;
  EXPECT_EQ((*settings)[0].raw, 6554);
  EXPECT_EQ((*settings)[0].RoundingNote(),
            "position_kp: 0.1 will be stored as 0.100006103515625 (the nearest step of "
            "1/65536)");
}

}  // namespace
