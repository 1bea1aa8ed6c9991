// run.json, the output folder a run writes, and mjc's config file: strict loaders and
// no run written over another.
#include "mjc/host/run_record.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "mjc/host/config.h"
#include "mjc/host/report.h"
#include "mjc/host/units.h"

namespace {

using namespace mjc;
using namespace mjc::host;
namespace fs = std::filesystem;

RunRecord Example() {
  RunRecord r;
  r.command = "trial";
  r.node = 2;
  r.iface = "vcan0";
  protocol::BoardInfo info;
  info.build = 0x1958ba84;
  info.dirty = true;
  info.reset_cause = protocol::ResetCause::kWatchdog;
  info.instance = 0x3f2a;
  r.board = info;
  BoardCalibration held;
  held.calibrated = true;
  held.record.backlash.c_right = Angle::Quantize(DegToRad(1.1));
  held.record.backlash.c_left = Angle::Quantize(DegToRad(-0.9));
  held.record.backlash.alpha = Scale::Quantize(1.0);
  held.record.sea_stiffness = Stiffness::Quantize(0.63);
  held.record.joint_zero_count = 123;
  r.calibration = held;
  r.subject = "S07";
  r.protocol = "amplitude";
  r.amplitudes_deg = {6, 15.5};
  r.frequency_hz = 0.5;
  r.repetitions = 5;
  r.rest_s = 1.5;
  r.started_utc = "2026-11-24T10:31:05Z";
  r.host = "lab";
  r.mjc = "1958ba84-dirty";
  r.end.outcome = "faulted";
  r.end.fault_code = 303;
  r.end.message = "trial 1/2 on node 2: the board faulted";
  return r;
}

TEST(RunRecord, RoundTripsThroughJson) {
  const RunRecord written = Example();
  const nlohmann::json j = RunRecordToJson(written);
  EXPECT_TRUE(j["robot"].is_null());  // room for a robot description, none invented
  EXPECT_EQ(j["board"]["build"], "1958ba84");
  EXPECT_EQ(j["board"]["instance"], "3f2a");
  EXPECT_EQ(j["board"]["reset_cause"], "watchdog");
  EXPECT_EQ(j["end"]["fault"]["name"], "CAN bus-off");
  std::string why;
  const auto read = RunRecordFromJson(j, &why);
  ASSERT_TRUE(read) << why;
  EXPECT_EQ(read->node, 2);
  ASSERT_TRUE(read->board);
  EXPECT_EQ(read->board->build, 0x1958ba84u);
  EXPECT_TRUE(read->board->dirty);
  EXPECT_EQ(read->board->reset_cause, protocol::ResetCause::kWatchdog);
  EXPECT_EQ(read->board->instance, 0x3f2a);
  ASSERT_TRUE(read->calibration);
  EXPECT_EQ(read->calibration->record.backlash.c_right,
            written.calibration->record.backlash.c_right);
  EXPECT_EQ(read->calibration->record.joint_zero_count, 123);
  EXPECT_EQ(read->subject, "S07");
  EXPECT_EQ(read->amplitudes_deg, written.amplitudes_deg);
  EXPECT_EQ(read->end.outcome, "faulted");
  EXPECT_EQ(read->end.fault_code, 303);
  EXPECT_EQ(RunRecordToJson(*read), j);
}

TEST(RunRecord, IsStrict) {
  std::string why;
  nlohmann::json j = RunRecordToJson(Example());
  j["amplitude_deg"] = j["amplitudes_deg"];
  j.erase("amplitudes_deg");
  EXPECT_FALSE(RunRecordFromJson(j, &why));
  EXPECT_EQ(why,
            "run.json: unknown key 'amplitude_deg' (did you mean 'amplitudes_deg'?)");
  j = RunRecordToJson(Example());
  j["board"]["instanse"] = "3f2a";
  EXPECT_FALSE(RunRecordFromJson(j, &why));
  EXPECT_EQ(why,
            "run.json: unknown key 'board.instanse' (did you mean 'board.instance'?)");
  j = RunRecordToJson(Example());
  j["end"]["outcome"] = "finished";
  EXPECT_FALSE(RunRecordFromJson(j, &why));
  EXPECT_NE(why.find("'end.outcome' \"finished\" is unknown"), std::string::npos) << why;
  j = RunRecordToJson(Example());
  j["format"] = "mjc run 9";
  EXPECT_FALSE(RunRecordFromJson(j, &why));
  j = RunRecordToJson(Example());
  j["board"] = nullptr;  // an older image sends no BoardInfo
  j["calibration"] = nullptr;
  j["subject"] = nullptr;
  EXPECT_TRUE(RunRecordFromJson(j, &why)) << why;
}

// What decided the run travels with it: the robot description's content, the board's
// parameters, the cable friction in force, and the process that wrote it.
TEST(RunRecord, CarriesTheRobotItsParametersAndItsProcess) {
  RunRecord r = Example();
  r.command = "calibrate";
  r.protocol = "calibration sweep";
  r.end = {"completed", std::nullopt, ""};
  const std::string text =
      ReadFileText(std::string(MJC_SOURCE_DIR) + "/robots/maestro-default.json")
          .value_or("");
  ASSERT_FALSE(text.empty());
  r.robot = RobotRecord("robots/maestro-default.json", text);
  r.params = {{"velocity_window", 101}, {"attachment_prior_stiffness", 0.5}};
  r.pid = 4242;
  r.calibration->record.backlash.cable_friction = Torque::Quantize(0.125);
  const nlohmann::json j = RunRecordToJson(r);
  EXPECT_EQ(j["format"], "mjc run 2");
  EXPECT_EQ(j["robot"]["description"], nlohmann::json::parse(text));
  std::string why;
  const auto read = RunRecordFromJson(j, &why);
  ASSERT_TRUE(read) << why;
  EXPECT_EQ(read->pid, 4242);
  EXPECT_EQ(read->params["velocity_window"], 101);
  EXPECT_EQ(read->calibration->record.backlash.cable_friction, Torque::Quantize(0.125));
  EXPECT_EQ(RunRecordToJson(*read), j);
  // A description the loader would refuse, a parameter the list does not have or out of
  // its range, are refused in run.json too.
  nlohmann::json bad = j;
  bad["robot"]["description"]["springs"]["rate_N_per_m"] = 1e9;
  EXPECT_FALSE(RunRecordFromJson(bad, &why));
  EXPECT_NE(why.find("springs"), std::string::npos) << why;
  bad = j;
  bad["params"]["velocity_widow"] = 31;
  EXPECT_FALSE(RunRecordFromJson(bad, &why));
  EXPECT_NE(why.find("did you mean 'velocity_window'"), std::string::npos) << why;
  bad = j;
  bad["params"]["torque_max"] = -3;
  EXPECT_FALSE(RunRecordFromJson(bad, &why));
  EXPECT_NE(why.find("field 'params.torque_max' = -3 is outside"), std::string::npos)
      << why;
  // A version 1 file (no pid, params or cable friction) is still read.
  nlohmann::json v1 = RunRecordToJson(Example());
  v1["format"] = "mjc run 1";
  v1.erase("pid");
  v1.erase("params");
  v1["calibration"].erase("cable_friction_Nm");
  EXPECT_TRUE(RunRecordFromJson(v1, &why)) << why;
}

// Values no run can have had are refused, naming the field.
TEST(RunRecord, RefusesValuesNoRunCanHave) {
  struct Case {
    const char* key;
    nlohmann::json value;
    const char* said;
  };
  const Case cases[] = {
      {"protocol", "xyz", "field 'protocol' \"xyz\" is none of"},
      {"protocol", "amplitud", "(did you mean \"amplitude\"?)"},
      {"protocol", "calibration sweep", "is not a protocol of mjc trial"},
      {"command", "trail", "(did you mean \"trial\"?)"},
      {"frequency_hz", 1e300, "field 'frequency_hz' = 1e+300 is outside [0.08, 5] Hz"},
      {"frequency_hz", -0.5, "is outside [0.08, 5]"},
      {"rest_s", 99, "field 'rest_s' = 99 is outside"},
      {"amplitudes_deg", {6, 900}, "field 'amplitudes_deg[1]' = 900 is outside [1, 90]"},
      {"amplitudes_deg", nlohmann::json::array(), "field 'amplitudes_deg' is empty"},
      {"repetitions", 0, "field 'repetitions'"},
  };
  for (const Case& c : cases) {
    nlohmann::json j = RunRecordToJson(Example());
    j[c.key] = c.value;
    std::string why;
    EXPECT_FALSE(RunRecordFromJson(j, &why)) << c.key;
    EXPECT_NE(why.find(c.said), std::string::npos) << why;
  }
  nlohmann::json j = RunRecordToJson(Example());
  j["end"]["outcome"] = "completed";  // with a fault
  std::string why;
  EXPECT_FALSE(RunRecordFromJson(j, &why));
  EXPECT_NE(why.find("'end.fault' is given, but the outcome is not"), std::string::npos)
      << why;
}

class Folders : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  const fs::path dir_ =
      fs::temp_directory_path() / ("mjc_run_record_" + std::to_string(::getpid()));
};

TEST_F(Folders, RunRecordIsWrittenAndReadBack) {
  std::string why;
  EXPECT_FALSE(ReadRunRecord(dir_, &why));
  EXPECT_EQ(why, "");  // none: a folder from before run.json
  WriteRunRecord(Example(), dir_);
  const auto read = ReadRunRecord(dir_, &why);
  ASSERT_TRUE(read) << why;
  EXPECT_EQ(read->subject, "S07");
  std::ofstream(dir_ / "run.json") << "{\"format\": ";
  EXPECT_FALSE(ReadRunRecord(dir_, &why));
  EXPECT_NE(why.find("not valid JSON"), std::string::npos) << why;
  // Rewritten whole through a temporary: none is left behind.
  WriteRunRecord(Example(), dir_);
  EXPECT_FALSE(fs::exists(dir_ / "run.json.tmp"));
  const std::string good = RunRecordToJson(Example()).dump(2);
  // Anything after the object, and a key given twice, are refused, not ignored.
  std::ofstream(dir_ / "run.json", std::ios::trunc) << good << "\n{}\n";
  EXPECT_FALSE(ReadRunRecord(dir_, &why));
  EXPECT_NE(why.find("not valid JSON"), std::string::npos) << why;
  std::string twice = good;
  twice.insert(twice.find("\"node\""), "\"node\": 7,\n  ");
  std::ofstream(dir_ / "run.json", std::ios::trunc) << twice;
  EXPECT_FALSE(ReadRunRecord(dir_, &why));
  EXPECT_NE(why.find("key 'node' appears twice"), std::string::npos) << why;
}

// A run.json left saying "running": still going only while its process is an mjc on
// this host.
TEST(RunRecord, ARunningRecordWhoseProcessIsGoneIsTold) {
  RunRecord r = Example();
  r.end = {};
  r.host = HostName();
  r.pid = static_cast<long>(::getpid());  // alive, but not an mjc (the test)
  EXPECT_FALSE(RunStillGoing(r));
  r.pid = std::nullopt;
  EXPECT_FALSE(RunStillGoing(r));
}

TEST_F(Folders, ByDefaultEachRunGetsANewFolder) {
  const auto first = PrepareOutputFolder("", (dir_ / "trial").string(), false, {});
  const auto second = PrepareOutputFolder("", (dir_ / "trial").string(), false, {});
  EXPECT_TRUE(first.chosen);
  EXPECT_NE(first.path, second.path);  // the same second: a suffix
  EXPECT_TRUE(fs::is_directory(first.path));
  EXPECT_TRUE(fs::is_directory(second.path));
  // "2026-11-24T10-31-05Z": the UTC time, '-' for ':'.
  const std::string name = first.path.filename().string();
  ASSERT_EQ(name.size(), 20u) << name;
  EXPECT_EQ(name[10], 'T');
  EXPECT_EQ(name[13], '-');
  EXPECT_EQ(name.back(), 'Z');
}

TEST_F(Folders, AnUsedFolderOrAFileIsRefusedUnlessForced) {
  const fs::path used = dir_ / "used";
  fs::create_directories(used);
  std::ofstream(used / "windows.csv") << "old";
  std::ofstream(used / "notes.txt") << "the operator's";
  try {
    PrepareOutputFolder(used.string(), "unused", false, {"windows.csv"});
    FAIL() << "not refused";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("is not empty (notes.txt, windows.csv"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("--force"), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::exists(used / "windows.csv"));  // untouched
  const auto forced = PrepareOutputFolder(used.string(), "unused", true, {"windows.csv"});
  EXPECT_FALSE(forced.chosen);
  EXPECT_FALSE(fs::exists(used / "windows.csv"));  // an earlier run's output: replaced
  EXPECT_TRUE(fs::exists(used / "notes.txt"));     // not an output: kept
  std::ofstream(dir_ / "file") << "x";
  EXPECT_THROW(PrepareOutputFolder((dir_ / "file").string(), "", true, {}),
               std::runtime_error);
  // An empty folder is fine.
  fs::create_directories(dir_ / "empty");
  EXPECT_NO_THROW(PrepareOutputFolder((dir_ / "empty").string(), "", false, {}));
}

TEST(ToolConfig, IsStrictAndRangeChecked) {
  std::string why;
  const auto config = ParseToolConfig(R"({"iface": "can0", "node": 2})", "c.json", &why);
  ASSERT_TRUE(config) << why;
  EXPECT_EQ(config->iface, "can0");
  EXPECT_EQ(config->node, 2);
  EXPECT_TRUE(ParseToolConfig("{}", "c.json", &why));
  EXPECT_FALSE(ParseToolConfig(R"({"ifcae": "can0"})", "c.json", &why));
  EXPECT_EQ(why, "c.json: unknown key 'ifcae' (did you mean 'iface'?)");
  EXPECT_FALSE(ParseToolConfig(R"({"node": 9})", "c.json", &why));
  EXPECT_EQ(why, "c.json: 'node' must be an integer in 1..8, not 9");
  EXPECT_FALSE(ParseToolConfig(R"({"iface": "can 0"})", "c.json", &why));
  EXPECT_FALSE(ParseToolConfig("[", "c.json", &why));
  EXPECT_EQ(why.rfind("c.json: not valid JSON", 0), 0u);
}

TEST(ToolConfig, TheEnvironmentNamesTheFileAndTheInterface) {
  const fs::path file =
      fs::temp_directory_path() / ("mjc_config_" + std::to_string(::getpid()) + ".json");
  std::ofstream(file) << R"({"iface": "can1", "node": 3})";
  ::setenv("MJC_CONFIG", file.c_str(), 1);
  ::unsetenv("MJC_IFACE");
  std::string why;
  auto config = LoadToolConfig(&why);
  ASSERT_TRUE(config) << why;
  EXPECT_EQ(config->iface, "can1");
  EXPECT_EQ(config->node, 3);
  ::setenv("MJC_IFACE", "vcan5", 1);  // over the file's
  config = LoadToolConfig(&why);
  ASSERT_TRUE(config) << why;
  EXPECT_EQ(config->iface, "vcan5");
  EXPECT_EQ(config->node, 3);
  fs::remove(file);
  EXPECT_FALSE(LoadToolConfig(&why));  // named, and missing: an error
  EXPECT_NE(why.find("named by MJC_CONFIG"), std::string::npos) << why;
  ::unsetenv("MJC_CONFIG");
  ::unsetenv("MJC_IFACE");
}

}  // namespace
