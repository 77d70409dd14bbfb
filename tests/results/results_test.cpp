// The results writer (tools/results): what every summary.json and bench.json is written with.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

#include "results.hpp"

namespace snapnav::results {
namespace {

namespace fs = std::filesystem;

// A fresh folder under the system's temporary folder, removed at the end of the test.
class ResultsFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("snapnav_results_test_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  static std::string Text(const fs::path& p) {
    std::ifstream f(p);
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
  }
  fs::path dir_;
};

// The message of the std::runtime_error `f` throws ("" when it throws none).
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

TEST(Results, NanAndInfinitiesAreNull) {
  EXPECT_TRUE(Number(std::numeric_limits<double>::quiet_NaN()).is_null());
  EXPECT_TRUE(Number(std::numeric_limits<double>::infinity()).is_null());
  EXPECT_TRUE(Number(-std::numeric_limits<double>::infinity()).is_null());
  EXPECT_TRUE(Rounded(std::nan(""), 3).is_null());
  EXPECT_EQ(Number(1.5).get<double>(), 1.5);
  Json j;
  j["missing_m"] = Number(std::nan(""));
  EXPECT_EQ(j.dump(), "{\"missing_m\":null}");
}

TEST(Results, RoundedKeepsTheDigitsAReportPrints) {
  EXPECT_EQ(Rounded(0.123456, 4).get<double>(), 0.1235);
  EXPECT_EQ(Rounded(2.0, 2).dump(), "2.0");
  EXPECT_EQ(Rounded(-1.25e-6, 3).get<double>(), 0.0);
  EXPECT_EQ(Rounded(12345.678, 1).get<double>(), 12345.7);
}

TEST(Results, SignificantKeepsTheDigitsAStreamPrints) {
  EXPECT_EQ(Significant(0.123456789).get<double>(), 0.123457);
  EXPECT_EQ(Significant(123456789.0).get<double>(), 1.23457e8);
  EXPECT_EQ(Significant(2.5, 1).get<double>(), 2.0);
  EXPECT_EQ(Significant(600.0).dump(), "600");
  EXPECT_EQ(Significant(-3.0).dump(), "-3");
  EXPECT_EQ(Significant(1234567.0).dump(), "1234570.0");
  EXPECT_TRUE(Significant(std::numeric_limits<double>::infinity()).is_null());
}

TEST(Results, KeysKeepTheirOrder) {
  Json j;
  j["zeta"] = 1;
  j["alpha"] = 2;
  j["mid"] = 3;
  EXPECT_EQ(j.dump(), "{\"zeta\":1,\"alpha\":2,\"mid\":3}");
}

TEST(Results, StringsAreEscaped) {
  Json j;
  j["path"] = "a \"quoted\" dir\\with\nnewline\tand caf\xc3\xa9";
  EXPECT_EQ(j.dump(), "{\"path\":\"a \\\"quoted\\\" dir\\\\with\\nnewline\\tand caf\xc3\xa9\"}");
}

TEST_F(ResultsFiles, WrittenThenReadBack) {
  Json j;
  j["scene"] = "indoor13 \"two\"\nlines \xc3\xa9";
  j["runs"] = 3;
  j["ms_per_scan"] = 0.1;
  j["missing"] = Number(std::nan(""));
  j["figures"] = {"a.png", "b.png"};
  j["ms_runs"] = {1.5, 2.25, 3};
  const fs::path p = dir_ / "summary.json";
  WriteJsonFile(p.string(), j);
  const std::string text = Text(p);
  EXPECT_EQ(text.substr(0, 14), "{\n  \"scene\": \"");
  EXPECT_EQ(text.back(), '\n');
  const Json back = ReadJsonFile(p.string());
  EXPECT_EQ(back, j);
  std::string keys;
  for (const auto& [k, v] : back.items()) keys += k + " ";
  EXPECT_EQ(keys, "scene runs ms_per_scan missing figures ms_runs ");
  EXPECT_EQ(back["ms_per_scan"].get<double>(), 0.1);
  EXPECT_TRUE(back["missing"].is_null());
}

TEST_F(ResultsFiles, TruncatedFileNamesTheFileAndThePosition) {
  const fs::path p = dir_ / "bench.json";
  std::ofstream(p) << "{\n  \"runs\": 3,\n  \"ms\": [1, 2";
  const std::string e = ErrorOf([&] { ReadJsonFile(p.string()); });
  EXPECT_NE(e.find(p.string()), std::string::npos) << e;
  // 28 bytes: the end of the input is met at byte 29.
  EXPECT_NE(e.find("not JSON at byte 29: parse error at line 3, column 14"), std::string::npos) << e;
}

TEST_F(ResultsFiles, MissingFileIsNamed) {
  const fs::path p = dir_ / "none.json";
  const std::string e = ErrorOf([&] { ReadJsonFile(p.string()); });
  EXPECT_NE(e.find(p.string()), std::string::npos) << e;
}

TEST_F(ResultsFiles, WritingIntoAMissingFolderNamesThePath) {
  const fs::path p = dir_ / "no" / "such" / "summary.json";
  const std::string e = ErrorOf([&] { WriteJsonFile(p.string(), Json{{"runs", 1}}); });
  EXPECT_NE(e.find(p.string()), std::string::npos) << e;
  EXPECT_FALSE(fs::exists(p));
}

}  // namespace
}  // namespace snapnav::results
