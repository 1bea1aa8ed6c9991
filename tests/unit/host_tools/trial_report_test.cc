// Trial tables and windows.csv made of board windows.
#include "mjc/host/trial_report.h"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace mjc;
using namespace mjc::host;

// Trial tables and windows.csv.

BoardWindow Flexion(std::uint16_t repetition, double eta_percent, bool eta_valid) {
  BoardWindow w;
  w.motion = Motion::kFlexion;
  w.repetition = repetition;
  w.eta_percent = eta_percent;
  w.eta_valid = eta_valid;
  w.loading_J = 0.010;
  w.unloading_J = -0.005;
  w.positive_J = 0.011;
  w.negative_J = -0.006;
  return w;
}

TEST(TrialTables, InvalidEtaIsLeftOutOfTheStatisticsAndSaidSo) {
  // Five repetitions: the middle three flexions are 1, 2, 3; 3's η is invalid (its
  // value must not count), 0 and 4 are outside the analysis.
  TrialWindows trial{25.0,
                     5,
                     {Flexion(0, 10, true), Flexion(1, 40, true), Flexion(2, 50, true),
                      Flexion(3, 99, false), Flexion(4, 10, true)}};
  const std::string tables = TrialTables({trial}, true);
  // mean(40, 50) = 45, sample std = √((25 + 25) / 1) = 7.071.
  EXPECT_NE(tables.find("| 1 | 45.00% | 7.071% |"), std::string::npos) << tables;
  EXPECT_NE(tables.find("| overall | 45.00% | 7.071% |"), std::string::npos) << tables;
  EXPECT_NE(tables.find("leaves out 1 "), std::string::npos) << tables;
  // The amplitude table still counts the invalid window's energies (3 × 10 mJ).
  const std::string amplitude = TrialTables({trial}, false);
  EXPECT_NE(amplitude.find("| 25° | 10.000 ± 0.000 |"), std::string::npos) << amplitude;
  EXPECT_NE(amplitude.find("| 45.0% |"), std::string::npos) << amplitude;
}

TEST(TrialTables, NoValidEtaReadsNotAvailable) {
  TrialWindows trial{25.0, 3, {Flexion(1, 40, false)}};
  EXPECT_NE(TrialTables({trial}, true).find("| 1 | n/a | n/a |"), std::string::npos);
}

class WindowsCsv : public ::testing::Test {
 protected:
  void SetUp() override {
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  // Its own folder per process: ctest runs each test as a process, in parallel.
  const std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                                     ("mjc_windows_csv_" + std::to_string(::getpid()));
};

TEST_F(WindowsCsv, RoundTripsEveryWindowAndDerivesTheRepetitions) {
  BoardWindow extension = Flexion(4, 0, false);
  extension.motion = Motion::kExtension;
  const std::vector<TrialWindows> written = {
      {6.0, 5, {Flexion(0, 41.5, true), Flexion(3, 99, false), extension}},
      {8.0, 5, {Flexion(1, 47.25, true)}}};
  WriteWindowsCsv(written, dir_);
  std::string why;
  const auto read = ReadWindowsCsv(dir_, &why);
  ASSERT_TRUE(read) << why;
  ASSERT_EQ(read->size(), 2u);
  const TrialWindows& first = (*read)[0];
  EXPECT_EQ(first.amplitude_deg, 6.0);
  EXPECT_EQ(first.repetitions, 5);  // repetitions 0..4
  ASSERT_EQ(first.windows.size(), 3u);
  EXPECT_TRUE(first.windows[0].eta_valid);
  EXPECT_EQ(first.windows[0].eta_percent, 41.5);
  EXPECT_FALSE(first.windows[1].eta_valid);
  EXPECT_EQ(first.windows[1].positive_J, 0.011);
  EXPECT_EQ(first.windows[1].negative_J, -0.006);
  EXPECT_EQ(first.windows[2].motion, Motion::kExtension);
  EXPECT_EQ((*read)[1].repetitions, 5);  // as planned, not as seen
  EXPECT_FALSE(SameAmplitude(*read));
}

TEST_F(WindowsCsv, CountsFromOneAndSaysSoAndWhatIsAnalysed) {
  WriteWindowsCsv({{25.0, 5, {Flexion(0, 40, true), Flexion(2, 45, true)}}}, dir_);
  std::stringstream text;
  text << std::ifstream(dir_ / "windows.csv").rdbuf();
  const std::string csv = text.str();
  EXPECT_EQ(
      csv.rfind("# mjc windows.csv version 3: trial and repetition count from 1", 0), 0u)
      << csv;
  // Repetition 0 (the board's count) is the first, outside the middle three; 2 is the
  // third, analysed.
  EXPECT_NE(csv.find("\n1,25,5,flexion,1,0,1,40,"), std::string::npos) << csv;
  EXPECT_NE(csv.find("\n1,25,5,flexion,3,1,1,45,"), std::string::npos) << csv;
  int version = 0;
  std::string why;
  const auto read = ReadWindowsCsv(dir_, &why, &version);
  ASSERT_TRUE(read) << why;
  EXPECT_EQ(version, 3);
  EXPECT_EQ((*read)[0].windows[0].repetition, 0);
  EXPECT_EQ((*read)[0].windows[1].repetition, 2);
}

TEST_F(WindowsCsv, CarriesTheAttachmentFit) {
  BoardWindow w = Flexion(2, 45, true);
  w.fit_valid = true;
  w.stiffness_Nm_rad = 4.52;
  w.damping_Nms_rad = 0.251;
  w.offset_Nm = 0.0121;
  w.residual_rms_Nm = 0.0007;
  WriteWindowsCsv({{25.0, 5, {Flexion(1, 40, true), w}}}, dir_);
  std::string why;
  const auto read = ReadWindowsCsv(dir_, &why);
  ASSERT_TRUE(read) << why;
  const BoardWindow& back = (*read)[0].windows[1];
  EXPECT_TRUE(back.fit_valid);
  EXPECT_FALSE((*read)[0].windows[0].fit_valid);
  EXPECT_DOUBLE_EQ(back.stiffness_Nm_rad, 4.52);
  EXPECT_DOUBLE_EQ(back.damping_Nms_rad, 0.251);
  EXPECT_DOUBLE_EQ(back.offset_Nm, 0.0121);
  EXPECT_DOUBLE_EQ(back.residual_rms_Nm, 0.0007);
  // Repetitions 1 and 2 are analysed (the middle three of five); only 2 has a fit.
  const std::string table = AttachmentTable(*read);
  EXPECT_NE(table.find("| 1 | 25° | 4.520 | 0.2510 | 0.0121 | 0.00070 | 1/2 |"),
            std::string::npos)
      << table;
}

TEST_F(WindowsCsv, AVersionOneFileIsReadCountingFromZero) {
  std::ofstream(dir_ / "windows.csv")
      << "trial,amplitude_deg,motion,repetition,eta_valid,eta_pct,loading_J,"
         "unloading_J,net_J,positive_J,negative_J,peak_power_W,peak_torque_Nm\n"
         "1,25,flexion,0,1,40,0.01,-0.005,0.005,0.011,-0.006,0.01,0.1\n"
         "1,25,flexion,4,1,42,0.01,-0.005,0.005,0.011,-0.006,0.01,0.1\n";
  int version = 0;
  std::string why;
  const auto read = ReadWindowsCsv(dir_, &why, &version);
  ASSERT_TRUE(read) << why;
  EXPECT_EQ(version, 1);
  EXPECT_EQ((*read)[0].repetitions, 5);
  EXPECT_EQ((*read)[0].windows[1].repetition, 4);
}

TEST(TrialTables, SayWhatThePlusMinusIs) {
  TrialWindows trial{25.0, 5, {Flexion(1, 40, true), Flexion(2, 50, true)}};
  EXPECT_NE(TrialTables({trial}, false)
                .find("Each energy: mean ± standard error of the mean (sample standard "
                      "deviation / √n) over the middle three flexions (repetitions 2-4 "
                      "of 5)"),
            std::string::npos)
      << TrialTables({trial}, false);
  EXPECT_NE(TrialTables({trial}, true).find("sample standard deviation (n − 1)"),
            std::string::npos);
}

TEST_F(WindowsCsv, AFileOfAnotherLayoutIsRefusedWithTheReason) {
  std::ofstream(dir_ / "windows.csv")
      << "trial,amplitude_deg,motion,repetition,eta_pct,loading_J,unloading_J,net_J,"
         "peak_power_W,peak_torque_Nm\n1,25,flexion,0,40,0.01,-0.005,0.005,0.01,0.1\n";
  std::string why;
  EXPECT_FALSE(ReadWindowsCsv(dir_, &why));
  EXPECT_NE(why.find("the header is not"), std::string::npos) << why;
}

TEST_F(WindowsCsv, AnUnknownMotionIsMalformed) {
  WriteWindowsCsv({{25.0, 5, {Flexion(1, 40, true)}}}, dir_);
  std::stringstream read;
  read << std::ifstream(dir_ / "windows.csv").rdbuf();
  std::string text = read.str();
  text.replace(text.find(",flexion,"), 9, ",sideways,");
  std::ofstream(dir_ / "windows.csv") << text;
  std::string why;
  EXPECT_FALSE(ReadWindowsCsv(dir_, &why));
  // After the note and header, naming the column.
  EXPECT_NE(why.find("line 3, motion: 'sideways' is not flexion or extension"),
            std::string::npos)
      << why;
}

TEST_F(WindowsCsv, AnUnwritableFolderThrowsNamingTheFile) {
  const auto missing = dir_ / "no" / "such" / "folder";
  try {
    WriteWindowsCsv({}, missing);
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find((missing / "windows.csv").string()),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("No such file"), std::string::npos) << e.what();
  }
}

// The file as WriteWindowsCsv wrote it, with `from` replaced by `to` in its row
// number `row` (counted from 1 below the header).
std::string Edited(const std::filesystem::path& dir, int row, const std::string& from,
                   const std::string& to) {
  std::stringstream read;
  read << std::ifstream(dir / "windows.csv").rdbuf();
  std::string text = read.str();
  std::size_t at = 0;
  for (int line = 0; line < row + 1; ++line) at = text.find('\n', at) + 1;
  const std::size_t end = text.find('\n', at);
  std::string line = text.substr(at, end - at);
  const std::size_t cell = line.find(from);
  EXPECT_NE(cell, std::string::npos) << line;
  line.replace(cell, from.size(), to);
  text.replace(at, end - at, line);
  return text;
}

// Each row that the board could not have sent, or that contradicts another, is refused
// naming its line and column; each case checked against the untouched file first.
TEST_F(WindowsCsv, RefusesWhatTheBoardCannotHaveSentNamingLineAndColumn) {
  const std::vector<TrialWindows> trials = {
      {25.0, 5, {Flexion(1, 40, true), Flexion(2, 45, true)}}};
  struct Case {
    int row;
    std::string from, to, said;
  };
  // Row 1's cells: 1,25,5,flexion,2,1,1,40,0.01,-0.005,0.005,0.011,-0.006,0,0,0,...
  const Case cases[] = {
      {1, ",40,", ",nan,", "line 3, eta_pct: 'nan' is not a finite decimal number"},
      {1, ",40,", ",inf,", "line 3, eta_pct: 'inf' is not a finite"},
      {1, ",0.011,", ",1e300,", "line 3, positive_J: 1e300 is outside [0, 128]"},
      {1, ",0.01,-0.005,0.005,", ",-0.01,-0.005,-0.015,",
       "line 3, loading_J: -0.01 is not positive, yet eta_valid"},
      {2, ",0.005,0.011,", ",0.007,0.011,", "line 4, net_J: 0.007 is not loading_J"},
      {2, ",-0.006,", ",0.006,", "line 4, negative_J: 0.006 is outside [-128, 0]"},
      {2, "1,25,", "1,26,", "line 4, amplitude_deg: 26° contradicts line 3's 25°"},
      {2, "1,25,5,", "1,25,7,", "line 4, repetitions: 7 contradicts line 3's 5"},
      {2, ",flexion,3,", ",flexion,2,",
       "line 4, the flexion of repetition 2 of trial 1 again (first on line 3)"},
      {2, ",flexion,3,1,", ",flexion,3,0,", "line 4, analysed: 0 contradicts the window"},
      {1, ",40,", ",140,", "line 3, eta_pct: 140 is above 100 %"},
      {1, "1,25,", "1,0.5,", "line 3, amplitude_deg: 0.5 is outside [1, 90]"},
  };
  for (const Case& c : cases) {
    WriteWindowsCsv(trials, dir_);
    std::string why;
    ASSERT_TRUE(ReadWindowsCsv(dir_, &why)) << why;
    const std::string text = Edited(dir_, c.row, c.from, c.to);
    std::ofstream(dir_ / "windows.csv", std::ios::trunc) << text;
    EXPECT_FALSE(ReadWindowsCsv(dir_, &why)) << c.to;
    EXPECT_NE(why.find(c.said), std::string::npos) << why;
  }
}

// A writer that dies: every window appended before its death is in the file, and a row
// cut in the middle (only a dying writer leaves one) is left out and said.
TEST_F(WindowsCsv, AWriterKilledMidRunLeavesEveryWindowItAppended) {
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    WindowsCsvWriter csv(dir_);
    csv.Append(0, 25.0, 5, Flexion(0, 40, true));
    csv.Append(0, 25.0, 5, Flexion(1, 41, true));
    csv.Append(1, 25.0, 5, Flexion(0, 42, true));
    ::kill(::getpid(), SIGKILL);  // no destructor, no flush, no exit handler
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  std::string why;
  bool cut = true;
  const auto read = ReadWindowsCsv(dir_, &why, nullptr, &cut);
  ASSERT_TRUE(read) << why;
  EXPECT_FALSE(cut);
  ASSERT_EQ(read->size(), 2u);
  EXPECT_EQ((*read)[0].windows.size(), 2u);
  EXPECT_EQ((*read)[1].windows[0].eta_percent, 42);
  // Half a row more, as a writer killed inside its write would leave.
  std::ofstream(dir_ / "windows.csv", std::ios::app) << "2,25,5,flexion,2,1,1,4";
  const auto again = ReadWindowsCsv(dir_, &why, nullptr, &cut);
  ASSERT_TRUE(again) << why;
  EXPECT_TRUE(cut);
  EXPECT_EQ((*again)[1].windows.size(), 1u);
}

// The figure, drawn by gnuplot on the host (the kernel-layer scripts draw none: a
// figure needs no CAN, and gnuplot under emulation took 14 s).
TEST_F(WindowsCsv, TheFigureIsAPngOfEveryTrial) {
  const std::vector<TrialWindows> trials = {
      {15.0, 5, {Flexion(1, 40, true), Flexion(2, 45, true), Flexion(3, 50, true)}},
      {25.0, 5, {Flexion(1, 42, true), Flexion(2, 47, true), Flexion(3, 52, true)}}};
  std::filesystem::create_directories(dir_);
  WriteWindowsCsv(trials, dir_);
  std::string why;
  for (const bool repeatability : {true, false}) {
    std::filesystem::remove(dir_ / "eta.png");
    ASSERT_TRUE(PlotTrials(dir_, repeatability, "a title", &why)) << why;
    // gnuplot's chatter stays in its log, removed once it succeeded.
    EXPECT_FALSE(std::filesystem::exists(dir_ / "eta.gp.log"));
    std::ifstream png(dir_ / "eta.png", std::ios::binary);
    char magic[8] = {};
    png.read(magic, sizeof magic);
    EXPECT_EQ(std::string(magic, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    EXPECT_GT(std::filesystem::file_size(dir_ / "eta.png"), 1000u);
  }
}

}  // namespace
