#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/options.hpp"
#include "snapnav/glue/slam_options.hpp"

namespace snapnav::glue {
namespace {

enum class Shape { kRound, kSquare };
const char* ShapeName(Shape s) { return s == Shape::kRound ? "round" : "square"; }

struct Inner {
  double sigma_m = 0.5;
};
struct Widget {
  double range_m = 4.0;
  int count = 3;
  double step_rad = 0.1;
  bool fast = false;
  std::string name = "w";
  Shape shape = Shape::kRound;
  Inner inner;
  void Validate() const {
    if (count < 1) throw std::invalid_argument("widget: count must be >= 1");
  }
};

const OptionTable<Widget>& Table() {
  static const auto table = OptionTable<Widget>()
                                .Number("range_m", "m", &Widget::range_m)
                                .Number("count", "", &Widget::count)
                                .Degrees("step_deg", &Widget::step_rad)
                                .Flag("fast", &Widget::fast)
                                .Text("name", &Widget::name)
                                .Choice("shape", &Widget::shape, {Shape::kRound, Shape::kSquare}, ShapeName)
                                .Number("sigma_m", "m", [](auto& w) -> auto& { return w.inner.sigma_m; });
  return table;
}

const char* kFile =
    "[w]\n"
    "range_m = 7.5\n"
    "count = 12\n"
    "step_deg = 90\n"
    "fast = true\n"
    "name = left\n"
    "shape = square\n"
    "sigma_m = 0.25\n";

TEST(OptionTable, ReadsEveryDeclaredKeyIntoItsField) {
  const IniFile ini = IniFile::Parse(kFile, "w.ini");
  const Widget w = Table().Read(ini, "w");
  EXPECT_DOUBLE_EQ(w.range_m, 7.5);
  EXPECT_EQ(w.count, 12);
  EXPECT_DOUBLE_EQ(w.step_rad, M_PI / 2);
  EXPECT_TRUE(w.fast);
  EXPECT_EQ(w.name, "left");
  EXPECT_EQ(w.shape, Shape::kSquare);
  EXPECT_DOUBLE_EQ(w.inner.sigma_m, 0.25);
  EXPECT_NO_THROW(ini.CheckAllUsed());
}

TEST(OptionTable, PrintsWhatItReadsBackInTheFileForm) {
  const Widget w = Table().Read(IniFile::Parse(kFile, "w.ini"), "w");
  std::ostringstream printed;
  printed << "[w]\n";
  Table().Print(printed, w);
  EXPECT_EQ(printed.str(), kFile);
  const Widget again = Table().Read(IniFile::Parse(printed.str(), "printed"), "w");
  EXPECT_DOUBLE_EQ(again.step_rad, w.step_rad);
  EXPECT_EQ(again.shape, w.shape);
}

TEST(OptionTable, DescribesKeysUnitsKindsAndDefaults) {
  const auto info = Table().Describe();
  ASSERT_EQ(info.size(), 7u);
  EXPECT_EQ(info[0].key, "range_m");
  EXPECT_EQ(info[0].unit, "m");
  EXPECT_EQ(info[0].kind, "number");
  EXPECT_EQ(info[0].default_value, "4");
  EXPECT_EQ(info[1].kind, "integer");
  EXPECT_EQ(info[2].unit, "deg");
  EXPECT_EQ(info[3].kind, "flag");
  EXPECT_EQ(info[3].default_value, "false");
  EXPECT_EQ(info[5].kind, "choice");
  EXPECT_EQ(info[5].choices, "round | square");
  EXPECT_EQ(info[5].default_value, "round");
}

std::string ErrorOf(const std::string& text) {
  try {
    Table().Read(IniFile::Parse(text, "w.ini"), "w");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(OptionTable, ErrorsNameFileLineSectionAndKey) {
  std::string text = kFile;
  // A missing key, a bad choice, a bad number and the struct's own check.
  EXPECT_NE(ErrorOf("[w]\nrange_m = 1\n").find("count"), std::string::npos);
  const std::string bad_shape = ErrorOf(std::string(kFile).replace(text.find("square"), 6, "oval"));
  EXPECT_NE(bad_shape.find("w.ini:7"), std::string::npos) << bad_shape;
  EXPECT_NE(bad_shape.find("round | square"), std::string::npos) << bad_shape;
  const std::string bad_number = ErrorOf(std::string(kFile).replace(text.find("7.5"), 3, "far"));
  EXPECT_NE(bad_number.find("w.ini:2"), std::string::npos) << bad_number;
  EXPECT_NE(bad_number.find("range_m"), std::string::npos) << bad_number;
  const std::string bad_count = ErrorOf(std::string(kFile).replace(text.find("12"), 2, "0"));
  EXPECT_NE(bad_count.find("w.ini:3"), std::string::npos) << bad_count;
  EXPECT_NE(bad_count.find("count must be >= 1"), std::string::npos) << bad_count;
}

TEST(OptionTable, ListsAreCommaSeparatedNames) {
  struct Channels {
    std::vector<std::string> names;
  };
  const auto table = OptionTable<Channels>().List("names", &Channels::names);
  const Channels c = table.Read(IniFile::Parse("[c]\nnames = POSE_EKF, POSE_LASER_SLAM ,X\n", "c.ini"), "c");
  EXPECT_EQ(c.names, (std::vector<std::string>{"POSE_EKF", "POSE_LASER_SLAM", "X"}));
  std::ostringstream printed;
  table.Print(printed, c);
  EXPECT_EQ(printed.str(), "names = POSE_EKF,POSE_LASER_SLAM,X\n");
  EXPECT_EQ(table.Describe()[0].kind, "list");
}

TEST(OptionTable, ShippedLaserSlamKeysAreEveryDeclaredKey) {
  // The declaration and the shipped file agree: every key of [laser_slam] that is not the node's
  // own (map_every_n_scans, backend) is declared, and nothing is declared that the file lacks.
  const IniFile ini = IniFile::Load(SNAPNAV_CONFIG_DIR "/laser_slam.ini");
  const auto keys = ini.Keys("laser_slam");
  size_t declared = LaserSlamOptionTable().size() + GraphSlamOptionTable().size();
  EXPECT_EQ(keys.size(), declared + 2);
  for (const auto& i : LaserSlamOptionTable().Describe()) EXPECT_TRUE(ini.Has("laser_slam", i.key)) << i.key;
  for (const auto& i : GraphSlamOptionTable().Describe()) EXPECT_TRUE(ini.Has("laser_slam", i.key)) << i.key;
}

}  // namespace
}  // namespace snapnav::glue
