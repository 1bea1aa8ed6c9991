// The report helpers (mjc/host/report.h) against values worked by hand: the summary
// statistics (sample standard deviation), RMSE and range of small sets whose answers
// are exact, the CSV table's text and number format, and the file and gnuplot failures
// said with their reasons.
#include "mjc/host/report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace mjc::host {
namespace {

std::string ReadAll(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::filesystem::path TempPath(const std::string& name) {
  return std::filesystem::path(::testing::TempDir()) / name;
}

TEST(Describe, SampleStatisticsOfAKnownSet) {
  // 2, 4, 4, 4, 5, 5, 7, 9: mean 5, squared deviations sum to 32, so the sample
  // variance is 32/7 and the standard error √(32/7)/√8 = √(4/7).
  const std::vector<double> v = {2, 4, 4, 4, 5, 5, 7, 9};
  const Stats s = Describe(v);
  EXPECT_EQ(s.n, 8);
  EXPECT_DOUBLE_EQ(s.mean, 5.0);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(32.0 / 7.0));
  EXPECT_DOUBLE_EQ(s.se, std::sqrt(4.0 / 7.0));
}

TEST(Describe, FewValues) {
  const Stats none = Describe({});
  EXPECT_EQ(none.n, 0);
  EXPECT_EQ(none.mean, 0.0);
  const std::vector<double> one = {-3.5};
  const Stats s = Describe(one);
  EXPECT_EQ(s.n, 1);
  EXPECT_EQ(s.mean, -3.5);
  EXPECT_EQ(s.std, 0.0);  // undefined for one value: 0, as documented
  EXPECT_EQ(s.se, 0.0);
}

TEST(Rmse, OfKnownDifferences) {
  // Differences 3, -4, 0, 0: mean square 25/4.
  const std::vector<double> a = {3, 0, 1, -2};
  const std::vector<double> b = {0, 4, 1, -2};
  EXPECT_DOUBLE_EQ(Rmse(a, b), 2.5);
  EXPECT_EQ(Rmse(a, a), 0.0);
  const std::vector<double> shorter = {1, 2};
  EXPECT_THROW(Rmse(a, shorter), std::invalid_argument);
  EXPECT_THROW(Rmse({}, {}), std::invalid_argument);
}

TEST(Range, MaxMinusMin) {
  const std::vector<double> v = {0.5, -1.25, 3.0, 2.0};
  EXPECT_EQ(Range(v), 4.25);
  EXPECT_EQ(Range({}), 0.0);
}

TEST(CsvTable, WritesHeaderAndRowsInOrder) {
  CsvTable t({"repetition", "eta_percent", "motion"});
  t.AddRow({"1", CsvTable::Number(12.5), "flexion"});
  t.AddRow({"2", CsvTable::Number(-0.125), "extension"});
  EXPECT_THROW(t.AddRow({"3", "4"}), std::invalid_argument);
  const auto path = TempPath("mjc_report_test.csv");
  t.Write(path);
  EXPECT_EQ(ReadAll(path),
            "repetition,eta_percent,motion\n1,12.5,flexion\n2,-0.125,extension\n");
  std::filesystem::remove(path);
}

TEST(CsvTable, NumbersRoundTripAFloatAndKeepNineDigits) {
  EXPECT_EQ(CsvTable::Number(0.1), "0.1");
  EXPECT_EQ(CsvTable::Number(1.0 / 3.0), "0.333333333");
  EXPECT_EQ(CsvTable::Number(123456789012.0), "1.23456789e+11");
  EXPECT_EQ(CsvTable::Number(-2.0), "-2");
  // Nine significant digits identify every float (IEEE 754 single) exactly.
  for (const float f : {3.14159274f, 1e-30f, 16777217.0f, 0.7f}) {
    EXPECT_EQ(std::strtof(CsvTable::Number(static_cast<double>(f)).c_str(), nullptr), f);
  }
}

TEST(WriteFile, ReplacesTheWholeFile) {
  const auto path = TempPath("mjc_report_write.txt");
  WriteFile(path, "a longer first text\n");
  WriteFile(path, "short\n");
  EXPECT_EQ(ReadAll(path), "short\n");
  std::filesystem::remove(path);
}

TEST(WriteFile, AMissingFolderIsAnErrorNamingThePath) {
  const auto path = TempPath("no_such_folder_mjc") / "out.csv";
  try {
    WriteFile(path, "x");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file or directory"), std::string::npos)
        << e.what();
  }
}

TEST(RunGnuplot, AFailingScriptSaysWhatGnuplotSaidAndKeepsItsLog) {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    GTEST_SKIP() << "gnuplot is not installed (scripts/setup installs gnuplot-nox)";
  }
  const auto dir = TempPath("mjc_report_gnuplot");
  std::filesystem::create_directories(dir);
  {
    std::ofstream(dir / "good.gp")
        << "set terminal dumb\nset output 'good.txt'\nplot x\n";
    std::ofstream(dir / "bad.gp") << "plot no_such_function_mjc(x)\n";
  }
  std::string why;
  EXPECT_TRUE(RunGnuplot(dir / "good.gp", &why)) << why;
  EXPECT_TRUE(std::filesystem::exists(dir / "good.txt"));
  EXPECT_FALSE(std::filesystem::exists(dir / "good.gp.log"));  // nothing to keep

  EXPECT_FALSE(RunGnuplot(dir / "bad.gp", &why));
  EXPECT_NE(why.find("gnuplot failed on " + (dir / "bad.gp").string()), std::string::npos)
      << why;
  EXPECT_NE(why.find("no_such_function_mjc"), std::string::npos) << why;
  EXPECT_TRUE(std::filesystem::exists(dir / "bad.gp.log"));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace mjc::host
