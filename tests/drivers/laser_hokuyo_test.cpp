// laser-hokuyo: config parsing, CObservation2DRangeScan -> laser_scan_t, the node with a
// scripted scan source on memq://, the port checks, and the binary without a sensor.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <deque>
#include <filesystem>
#include <regex>
#include <sstream>
#include <thread>

#include <mrpt/core/Clock.h>
#include <mrpt/core/exceptions.h>

#include "../support/config_errors.hpp"
#include "driver_test_util.hpp"
#include "laser_hokuyo_node.hpp"
#include "snapnav/glue/bus.hpp"

namespace snapnav::processes {
namespace {

using mrpt::obs::CObservation2DRangeScan;
using snapnav::testing::ScratchDir;

const std::string kShippedConfig = std::string(SNAPNAV_CONFIG_DIR) + "/laser_hokuyo.ini";
constexpr double kDeg = M_PI / 180.0;

std::string ConfigErrorOf(const std::string& text) {
  try {
    LaserHokuyoConfig::FromIni(glue::IniFile::Parse(text, "laser.ini"), "");
  } catch (const glue::ConfigError& e) {
    return e.what();
  }
  return "";
}

LaserHokuyoConfig TestConfig(const std::string& prefix, double timeout_s = 5.0) {
  std::ostringstream s;
  s << "[channels]\nscan = LASER_SCAN\n[hokuyo]\nserial_port = /dev/ttyACM0\nsensor_name = urg\n"
    << "sensor_x_m = 0.25\nsensor_y_m = -0.05\nsensor_theta_rad = 0.1\nfov_deg = 0\nintensity = false\n"
    << "no_scan_timeout_s = " << timeout_s << "\n";
  return LaserHokuyoConfig::FromIni(glue::IniFile::Parse(s.str(), "test.ini"), prefix);
}

// A URG-04LX-like scan as CHokuyoURG builds it: steps 44..725 of 1024 per turn.
CObservation2DRangeScan UrgScan(double unix_time_s) {
  CObservation2DRangeScan scan;
  const size_t n = 725 - 44 + 1;
  scan.aperture = static_cast<float>(n * 2 * M_PI / 1024);
  scan.rightToLeft = true;
  scan.maxRange = 5.6f;
  scan.timestamp = mrpt::Clock::fromDouble(unix_time_s);
  scan.resizeScan(n);
  for (size_t i = 0; i < n; ++i) {
    scan.setScanRange(i, 0.1f + 0.005f * static_cast<float>(i));
    scan.setScanRangeValidity(i, i % 10 != 3);
  }
  return scan;
}

CObservation2DRangeScan SmallScan(size_t n, double aperture_rad, bool right_to_left) {
  CObservation2DRangeScan scan;
  scan.aperture = static_cast<float>(aperture_rad);
  scan.rightToLeft = right_to_left;
  scan.maxRange = 4.0f;
  scan.timestamp = mrpt::Clock::fromDouble(1000.0);
  scan.resizeScan(n);
  for (size_t i = 0; i < n; ++i) {
    scan.setScanRange(i, 1.0f + static_cast<float>(i));
    scan.setScanRangeValidity(i, true);
  }
  return scan;
}

LaserScanOptions TestOptions() {
  LaserScanOptions o;
  o.sensor_name = "urg";
  o.sensor_x_m = 0.25;
  o.sensor_y_m = -0.05;
  o.sensor_theta_rad = 0.1;
  o.range_min_m = kHokuyoRangeMinM;
  return o;
}

// --- config ---

TEST(LaserHokuyoConfig, ShippedConfigLoads) {
  const auto config = LaserHokuyoConfig::FromIni(glue::IniFile::Load(kShippedConfig), "P_");
  EXPECT_EQ(config.scan_channel, "P_LASER_SCAN");
  EXPECT_EQ(config.hokuyo.serial_port, "/dev/ttyACM0");
  EXPECT_EQ(config.config_path, kShippedConfig);
  EXPECT_DOUBLE_EQ(config.scan.range_min_m, 0.02);
  EXPECT_GT(config.no_scan_timeout_s, 0);
  std::ostringstream printed;
  config.Print(printed);
  const auto again = LaserHokuyoConfig::FromIni(glue::IniFile::Parse(printed.str(), "printed"), "");
  EXPECT_EQ(again.hokuyo.serial_port, config.hokuyo.serial_port);
  EXPECT_DOUBLE_EQ(again.scan.sensor_theta_rad, config.scan.sensor_theta_rad);
}

TEST(LaserHokuyoConfig, EveryShippedKeyIsRequiredAndUnknownKeysAreErrors) {
  const std::string text = snapnav::testing::ReadTextFile(kShippedConfig);
  EXPECT_EQ(ConfigErrorOf(text), "");
  for (const char* key : {"scan", "serial_port", "sensor_name", "sensor_x_m", "sensor_y_m", "sensor_theta_rad",
                          "fov_deg", "intensity", "no_scan_timeout_s"}) {
    const std::string without = std::regex_replace(text, std::regex("(^|\n)" + std::string(key) + " *=[^\n]*"), "$1");
    ASSERT_NE(without, text) << key;
    EXPECT_NE(ConfigErrorOf(without).find("missing key '" + std::string(key) + "'"), std::string::npos) << key;
  }
  EXPECT_NE(ConfigErrorOf(text + "\n[hokuyo_extra]\nmotor_speed_rpm = 600\n").find("motor_speed_rpm"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(std::regex_replace(text, std::regex("fov_deg = 0"), "fov_deg = 400")).find("fov_deg"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(std::regex_replace(text, std::regex("no_scan_timeout_s = [0-9.]+"), "no_scan_timeout_s = 0"))
                .find("no_scan_timeout_s"),
            std::string::npos);
  EXPECT_NE(ConfigErrorOf(std::regex_replace(text, std::regex("sensor_x_m = [0-9.]+"), "sensor_x_m = abc"))
                .find("expected a number"),
            std::string::npos);
}

// --- CObservation2DRangeScan -> laser_scan_t ---

TEST(RangeScanToLaserScan, UrgScanKeepsBeamsAnglesAndMarksInvalidAsMaxRange) {
  const CObservation2DRangeScan scan = UrgScan(1700000000.25);
  const laser_scan_t msg = RangeScanToLaserScan(scan, TestOptions());
  EXPECT_EQ(msg.utime, 1700000000250000);
  EXPECT_EQ(msg.sensor_name, "urg");
  EXPECT_FLOAT_EQ(msg.sensor_x_m, 0.25f);
  EXPECT_FLOAT_EQ(msg.sensor_y_m, -0.05f);
  EXPECT_FLOAT_EQ(msg.sensor_theta_rad, 0.1f);
  EXPECT_FLOAT_EQ(msg.range_min_m, 0.02f);
  EXPECT_FLOAT_EQ(msg.range_max_m, 5.6f);
  ASSERT_EQ(msg.nranges, 682);
  ASSERT_EQ(msg.ranges_m.size(), 682u);
  EXPECT_EQ(msg.nintensities, 0);
  EXPECT_TRUE(msg.intensities.empty());
  // 682 steps of 360/1024 deg: about -119.9 .. +119.9 deg.
  const double aperture = 682 * 2 * M_PI / 1024;
  EXPECT_NEAR(msg.angle_min_rad, -aperture / 2, 1e-6);
  EXPECT_NEAR(msg.angle_increment_rad, aperture / 681, 1e-7);
  EXPECT_NEAR(msg.angle_min_rad / kDeg, -119.88, 0.01);
  EXPECT_NEAR((msg.angle_min_rad + 681 * msg.angle_increment_rad) / kDeg, 119.88, 0.01);
  for (size_t i = 0; i < 682; ++i) {
    const float expected = (i % 10 == 3) ? 5.6f : 0.1f + 0.005f * static_cast<float>(i);
    ASSERT_FLOAT_EQ(msg.ranges_m[i], expected) << i;
    // Every beam agrees with MRPT's own angle of that beam.
    ASSERT_NEAR(msg.angle_min_rad + i * msg.angle_increment_rad, scan.getScanAngle(i), 1e-5) << i;
  }
}

TEST(RangeScanToLaserScan, ClockwiseScansAreReversed) {
  const laser_scan_t msg = RangeScanToLaserScan(SmallScan(5, M_PI, false), TestOptions());
  ASSERT_EQ(msg.nranges, 5);
  EXPECT_NEAR(msg.angle_min_rad, -M_PI / 2, 1e-6);
  EXPECT_NEAR(msg.angle_increment_rad, M_PI / 4, 1e-6);
  EXPECT_EQ(msg.ranges_m, (std::vector<float>{5, 4, 3, 2, 1}));
  const laser_scan_t ccw = RangeScanToLaserScan(SmallScan(5, M_PI, true), TestOptions());
  EXPECT_EQ(ccw.ranges_m, (std::vector<float>{1, 2, 3, 4, 5}));
}

TEST(RangeScanToLaserScan, CopiesIntensitiesAndTreatsNonFiniteAsInvalid) {
  CObservation2DRangeScan scan = SmallScan(4, M_PI / 2, true);
  scan.setScanHasIntensity(true);
  for (size_t i = 0; i < 4; ++i) scan.setScanIntensity(i, static_cast<int>(100 * i + 7));
  scan.setScanRange(2, NAN);
  const laser_scan_t msg = RangeScanToLaserScan(scan, TestOptions());
  EXPECT_EQ(msg.nintensities, 4);
  EXPECT_EQ(msg.intensities, (std::vector<float>{7, 107, 207, 307}));
  EXPECT_EQ(msg.ranges_m, (std::vector<float>{1, 2, 4, 4}));
}

TEST(RangeScanToLaserScan, FovKeepsTheCentralBeams) {
  // 241 beams, one per degree over 240 degrees.
  auto options = TestOptions();
  options.fov_deg = 90;
  const laser_scan_t msg = RangeScanToLaserScan(SmallScan(241, 240 * kDeg, true), options);
  ASSERT_EQ(msg.nranges, 91);
  EXPECT_NEAR(msg.angle_min_rad, -45 * kDeg, 1e-6);
  EXPECT_NEAR(msg.angle_increment_rad, kDeg, 1e-7);
  EXPECT_FLOAT_EQ(msg.ranges_m.front(), 1.0f + 75);  // beam 75 of 241 is at -45 deg
  EXPECT_FLOAT_EQ(msg.ranges_m.back(), 1.0f + 165);
  options.fov_deg = 360;  // wider than the scan: every beam
  EXPECT_EQ(RangeScanToLaserScan(SmallScan(241, 240 * kDeg, true), options).nranges, 241);
}

TEST(RangeScanToLaserScan, RejectsScansItCannotDescribe) {
  const auto options = TestOptions();
  EXPECT_THROW(RangeScanToLaserScan(SmallScan(1, M_PI, true), options), std::invalid_argument);
  CObservation2DRangeScan no_time = SmallScan(5, M_PI, true);
  no_time.timestamp = INVALID_TIMESTAMP;
  EXPECT_THROW(RangeScanToLaserScan(no_time, options), std::invalid_argument);
  CObservation2DRangeScan no_range = SmallScan(5, M_PI, true);
  no_range.maxRange = 0;
  EXPECT_THROW(RangeScanToLaserScan(no_range, options), std::invalid_argument);
  auto narrow = options;
  narrow.fov_deg = 0.5;  // keeps one beam of a 1-degree scan
  EXPECT_THROW(RangeScanToLaserScan(SmallScan(241, 240 * kDeg, true), narrow), std::invalid_argument);
}

TEST(MrptTimestampToUtime, IsUnixMicroseconds) {
  EXPECT_EQ(MrptTimestampToUtime(mrpt::Clock::fromDouble(0.0)), 0);
  EXPECT_EQ(MrptTimestampToUtime(mrpt::Clock::fromDouble(1.5)), 1500000);
  const auto now = std::chrono::system_clock::now();
  const int64_t now_us = std::chrono::duration_cast<std::chrono::microseconds>(now.time_since_epoch()).count();
  EXPECT_NEAR(static_cast<double>(MrptTimestampToUtime(mrpt::Clock::now())), static_cast<double>(now_us), 1e6);
}

// --- the node with a scripted source ---

class ScriptedSource : public RangeScanSource {
 public:
  struct Item {
    PollResult result;
    CObservation2DRangeScan scan;
  };
  explicit ScriptedSource(std::deque<Item> items) : items_(std::move(items)) {}
  PollResult Poll(CObservation2DRangeScan* scan, std::string* error) override {
    if (items_.empty()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));  // like the driver's read timeout
      return PollResult::kNoScan;
    }
    Item item = std::move(items_.front());
    items_.pop_front();
    if (item.result == PollResult::kScan) *scan = item.scan;
    if (item.result == PollResult::kHardwareError) *error = "scripted failure";
    return item.result;
  }
  std::string description() const override { return "scripted scanner"; }

 private:
  std::deque<Item> items_;
};

TEST(LaserHokuyoNode, PublishesScansAndCountsFailures) {
  using R = RangeScanSource::PollResult;
  std::deque<ScriptedSource::Item> items;
  items.push_back({R::kScan, UrgScan(100.0)});
  items.push_back({R::kNoScan, {}});
  items.push_back({R::kHardwareError, {}});
  items.push_back({R::kScan, SmallScan(1, M_PI, true)});  // does not convert
  items.push_back({R::kScan, UrgScan(100.1)});
  items.push_back({R::kScan, SmallScan(5, M_PI, false)});

  glue::Bus bus("memq://");
  std::vector<laser_scan_t> out;
  bus.Subscribe<laser_scan_t>("L1_LASER_SCAN", [&](const laser_scan_t& m) { out.push_back(m); });
  std::ostringstream log;
  LaserHokuyoNode node(bus, TestConfig("L1_"), std::make_unique<ScriptedSource>(std::move(items)), &log);
  node.Run(3);
  while (bus.HandleOnce(0)) {
  }
  EXPECT_EQ(node.published(), 3);
  EXPECT_EQ(node.hardware_errors(), 1);
  EXPECT_EQ(node.conversion_errors(), 1);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].utime, 100000000);
  EXPECT_EQ(out[1].utime, 100100000);
  EXPECT_EQ(out[0].nranges, 682);
  EXPECT_EQ(out[0].sensor_name, "urg");
  EXPECT_FLOAT_EQ(out[0].sensor_x_m, 0.25f);
  EXPECT_FLOAT_EQ(out[0].range_min_m, 0.02f);
  EXPECT_FLOAT_EQ(out[0].ranges_m[3], out[0].range_max_m);          // invalid reading
  EXPECT_EQ(out[2].ranges_m, (std::vector<float>{5, 4, 3, 2, 1}));  // clockwise scan, reversed
  EXPECT_NE(log.str().find("scripted scanner: scripted failure"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("scan not converted"), std::string::npos) << log.str();
  std::ostringstream report;
  node.Report(report);
  EXPECT_NE(report.str().find("published 3 scans on L1_LASER_SCAN"), std::string::npos) << report.str();
}

TEST(LaserHokuyoNode, SilenceLongerThanTheTimeoutIsAnError) {
  glue::Bus bus("memq://");
  LaserHokuyoNode node(bus, TestConfig("L2_", 0.2),
                       std::make_unique<ScriptedSource>(std::deque<ScriptedSource::Item>{}));
  const auto start = std::chrono::steady_clock::now();
  try {
    node.Run(0);
    FAIL() << "expected a timeout";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("scripted scanner: no scan for 0.2 s"), std::string::npos) << e.what();
  }
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GE(elapsed_s, 0.2);
  EXPECT_LT(elapsed_s, 3.0);
}

// --- the serial port checks and MRPT's errors ---

TEST(CheckSerialPort, NamesWhatIsWrong) {
  ScratchDir dir;
  EXPECT_EQ(CheckSerialPort(dir / "ttyACM9"), "no such device");
  snapnav::testing::WriteTextFile(dir / "plain", "x");
  EXPECT_NE(CheckSerialPort(dir / "plain").find("not a character device"), std::string::npos);
  EXPECT_NE(CheckSerialPort(dir.path().string()).find("folder"), std::string::npos);
  EXPECT_EQ(CheckSerialPort("/dev/null"), "");  // a character device anyone may open
}

TEST(BriefMrptError, DropsTheStackTrace) {
  try {
    THROW_EXCEPTION("Error trying to open the serial port /dev/ttyX!!");
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("Call stack"), std::string::npos);  // what MRPT gives
    EXPECT_EQ(BriefMrptError(e), "Error trying to open the serial port /dev/ttyX!!");
  }
  EXPECT_EQ(BriefMrptError(std::runtime_error("\nplain message\n")), "plain message");
}

TEST(HokuyoUrgSource, MissingPortIsAClearError) {
  ScratchDir dir;
  HokuyoOptions options;
  options.serial_port = dir / "ttyACM9";
  try {
    HokuyoUrgSource source(options, "cfg/laser.ini");
    FAIL() << "opened a missing port";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "cannot open Hokuyo URG on " + options.serial_port +
                                         ": no such device. Plug in the sensor or set [hokuyo] serial_port in "
                                         "cfg/laser.ini");
  }
}

TEST(HokuyoUrgSource, MrptFailureIsAClearErrorWithoutStackTrace) {
  HokuyoOptions options;
  options.serial_port = "/dev/null";  // a character device, but not a serial port: MRPT throws
  try {
    HokuyoUrgSource source(options, "cfg/laser.ini");
    FAIL() << "opened /dev/null as a Hokuyo";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.rfind("cannot open Hokuyo URG on /dev/null: ", 0), 0u) << what;
    EXPECT_EQ(what.find("Call stack"), std::string::npos) << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_NE(what.find("cfg/laser.ini"), std::string::npos) << what;
  }
}

// --- the binary ---

TEST(LaserHokuyoBinary, WithoutDeviceExitsOneNamingThePort) {
  ScratchDir dir;
  const std::string port = dir / "ttyACM9";
  const std::string text = std::regex_replace(snapnav::testing::ReadTextFile(kShippedConfig),
                                              std::regex("serial_port = [^ ]+"), "serial_port = " + port);
  snapnav::testing::WriteTextFile(dir / "laser.ini", text);
  const auto r = snapnav::testing::RunCommand(snapnav::testing::BinDir() + "/laser-hokuyo --config " +
                                              (dir / "laser.ini") + " --lcm-url memq://");
  EXPECT_EQ(r.exit_status, 1) << r.output;
  EXPECT_NE(r.output.find("laser-hokuyo: error: cannot open Hokuyo URG on " + port +
                          ": no such device. Plug in the sensor or set [hokuyo] serial_port in " + (dir / "laser.ini")),
            std::string::npos)
      << r.output;
  EXPECT_EQ(r.output.find("MRPT exception"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("serial_port = " + port), std::string::npos) << "effective config printed\n" << r.output;
}

TEST(LaserHokuyoBinary, ShippedConfigWithoutSensorAndNotASerialPort) {
  const std::string bin = snapnav::testing::BinDir() + "/laser-hokuyo";
  const auto help = snapnav::testing::RunCommand(bin + " --help");
  EXPECT_EQ(help.exit_status, 0);
  EXPECT_NE(help.output.find("--max-scans"), std::string::npos);

  ScratchDir dir;
  const std::string text = std::regex_replace(snapnav::testing::ReadTextFile(kShippedConfig),
                                              std::regex("serial_port = [^ ]+"), "serial_port = /dev/null");
  snapnav::testing::WriteTextFile(dir / "null.ini", text);
  const auto null_port = snapnav::testing::RunCommand(bin + " --config " + (dir / "null.ini") + " --lcm-url memq://");
  EXPECT_EQ(null_port.exit_status, 1) << null_port.output;
  EXPECT_NE(null_port.output.find("laser-hokuyo: error: cannot open Hokuyo URG on /dev/null: "), std::string::npos)
      << null_port.output;
  EXPECT_EQ(null_port.output.find("Call stack"), std::string::npos) << null_port.output;

  if (std::filesystem::exists("/dev/ttyACM0")) GTEST_SKIP() << "a device is plugged in at /dev/ttyACM0";
  const auto r = snapnav::testing::RunCommand(bin + " --lcm-url memq://");
  EXPECT_EQ(r.exit_status, 1) << r.output;
  EXPECT_NE(r.output.find("laser-hokuyo: error: cannot open Hokuyo URG on /dev/ttyACM0: no such device. Plug in the "
                          "sensor or set [hokuyo] serial_port in " +
                          kShippedConfig),
            std::string::npos)
      << r.output;
}

// Every number of the shipped laser_hokuyo.ini made negative or NaN: each error names the file, the line
// and the key.
TEST(LaserHokuyoConfigFile, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(test_support::ExpectBadNumbersNamed(kShippedConfig,
                                                [](const glue::IniFile& ini) { LaserHokuyoConfig::FromIni(ini, ""); }),
            0);
}

}  // namespace
}  // namespace snapnav::processes
