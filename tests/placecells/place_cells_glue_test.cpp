// The place-cell glue: INI sections (every key required, bad values named), the memory file
// (round trip through a real file, corrupt files refused with the file and byte offset named),
// Localization -> place_cell_match_t / pose_t.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <vector>

#include "../support/config_errors.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/place_cells.hpp"
#include "test_lab.hpp"

namespace snapnav::processes::test {
namespace {

namespace fs = std::filesystem;

std::string ConfigError(std::initializer_list<Override> overrides) {
  try {
    Config("", overrides, "edited.ini");
  } catch (const glue::ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ConfigError";
  return "";
}

// A fresh folder under the test temp dir.
std::string TempDir(const std::string& name) {
  const fs::path dir = fs::path(testing::TempDir()) / ("placecells_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::vector<uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void WriteBytes(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// A memory of three cells of indoor13, with the shipped config's view options.
nav::PlaceCellMemory ThreeCellMemory() {
  const auto config = Config("", {});
  auto& lab = Indoor13::Get();
  nav::PlaceCellMemory memory(config.view, lab.panorama(), config.vocabulary);
  const std::vector<nav::Pose2> poses = {{2.5, 2.0, 0.0}, {3.5, 2.0, 1.0}, {4.5, 3.0, -2.0}};
  for (size_t i = 0; i < poses.size(); ++i) {
    memory.Add(poses[i], 1000000 * static_cast<int64_t>(i + 1), nav::MakePlaceView(lab.Panorama(poses[i]), config.view));
  }
  return memory;
}

bool SameMat(const cv::Mat& a, const cv::Mat& b) {
  if (a.empty() || b.empty()) return a.empty() && b.empty();
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

void ExpectSameSet(const nav::LandmarkSet& a, const nav::LandmarkSet& b, const std::string& what) {
  EXPECT_EQ(a.method, b.method) << what;
  EXPECT_EQ(a.width_px, b.width_px) << what;
  EXPECT_EQ(a.height_px, b.height_px) << what;
  ASSERT_EQ(a.size(), b.size()) << what;
  for (int i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a.landmarks[i].x_px, b.landmarks[i].x_px) << what << " " << i;
    EXPECT_EQ(a.landmarks[i].y_px, b.landmarks[i].y_px) << what << " " << i;
    EXPECT_EQ(a.landmarks[i].strength, b.landmarks[i].strength) << what << " " << i;
    EXPECT_EQ(a.landmarks[i].scale_px, b.landmarks[i].scale_px) << what << " " << i;
  }
  EXPECT_TRUE(SameMat(a.descriptors, b.descriptors)) << what << " descriptors";
}

TEST(PlaceCellsIni, ShippedConfigReads) {
  const auto c = Config("P_", {});
  EXPECT_EQ(c.mode, PlaceCellsMode::kLocalize);
  EXPECT_TRUE(c.raw_input);
  EXPECT_EQ(c.input_channel(), "P_OMNI_FRAME");
  EXPECT_EQ(c.match_channel, "P_PLACE_CELL_MATCH");
  EXPECT_EQ(c.pose_channel, "P_POSE_PLACE_CELLS");
  EXPECT_EQ(c.view.features.method, nav::LandmarkMethod::kSift);
  EXPECT_EQ(c.view.vline.window_px, 80);
  EXPECT_EQ(c.localizer.measure.measure, nav::PlaceMeasure::kBearingDifference);
  EXPECT_NEAR(c.localizer.measure.ransac_threshold_rad, 3 * M_PI / 180, 1e-12);
  EXPECT_TRUE(c.localizer.filter.enabled);
  EXPECT_EQ(c.vocabulary.branching, 8);
}

// The printed configuration is an INI file that reads back to the same options.
TEST(PlaceCellsIni, PrintReadsBack) {
  const auto c = Config("", {{"measure", "measure", "count"},
                             {"measure", "refinement", "ransac"},
                             {"landmarks", "method", "surf"},
                             {"localizer", "estimate", "nearest"},
                             {"placecells", "mode", "explore"}});
  std::ostringstream first;
  c.Print(first);
  const auto again = PlaceCellsConfig::FromIni(glue::IniFile::Parse(first.str(), "printed.ini"), "");
  std::ostringstream second;
  again.Print(second);
  EXPECT_EQ(first.str(), second.str());
  EXPECT_EQ(again.localizer.measure.measure, nav::PlaceMeasure::kMatchCount);
  EXPECT_EQ(again.localizer.measure.refinement, nav::MatchRefinement::kRansac);
  EXPECT_EQ(again.view.features.method, nav::LandmarkMethod::kSurf);
  EXPECT_EQ(again.localizer.estimate, nav::PlaceEstimate::kNearestCell);
  EXPECT_EQ(again.mode, PlaceCellsMode::kExplore);
}

TEST(PlaceCellsIni, MissingKeyIsNamed) {
  struct Case {
    const char* section;
    const char* key;
  };
  for (const Case k : {Case{"measure", "keep_min"}, Case{"distance_filter", "radius_m"}, Case{"vocabulary", "depth"},
                       Case{"place_view", "vline_window_px"}, Case{"localizer", "estimate"},
                       Case{"matching", "ratio"}, Case{"placecells", "min_travel_m"}, Case{"channels", "explore_pose"},
                       Case{"sift", "sigma"}}) {
    const std::string e = ConfigError({{k.section, k.key, nullptr}});
    EXPECT_NE(e.find(std::string("'") + k.key + "'"), std::string::npos) << e;
    EXPECT_NE(e.find(std::string("[") + k.section + "]"), std::string::npos) << e;
    EXPECT_NE(e.find("edited.ini"), std::string::npos) << e;
  }
}

TEST(PlaceCellsIni, BadValueIsNamed) {
  struct Case {
    Override o;
    const char* expect;  // in the message besides the file
  };
  for (const Case& c : {Case{{"measure", "measure", "euclid"}, "bearing | count | vline"},
                        Case{{"measure", "refinement", "best"}, "smallest | ransac"},
                        Case{{"localizer", "estimate", "mean"}, "nearest | interpolated"},
                        Case{{"measure", "keep_fraction", "half"}, "keep_fraction = 'half': expected a number"},
                        Case{{"measure", "keep_fraction", "1.5"}, "[measure] place cells: keep_fraction"},
                        Case{{"distance_filter", "weight", "2"}, "[distance_filter] place cells: filter weight"},
                        Case{{"distance_filter", "enabled", "maybe"}, "enabled = 'maybe': expected true or false"},
                        Case{{"vocabulary", "branching", "1"}, "[vocabulary] vocabulary: branching"},
                        Case{{"vocabulary", "seed", "-3"}, "[vocabulary] seed = '-3': must be >= 0"},
                        Case{{"place_view", "window_px", "2"}, "[place_view] place cells: window_px"},
                        Case{{"landmarks", "method", "vline"}, "method = 'vline': expected sift | surf"},
                        Case{{"placecells", "mode", "map"}, "explore | localize"},
                        Case{{"placecells", "novelty_threshold", "-1"}, "novelty_threshold"},
                        Case{{"placecells", "memory_file", ""}, "memory_file"},
                        Case{{"channels", "match", "OMNI_FRAME"}, "match and omni are both 'OMNI_FRAME'"}}) {
    const std::string e = ConfigError({c.o});
    EXPECT_NE(e.find(c.expect), std::string::npos) << c.o.section << " " << c.o.key << ": " << e;
    EXPECT_NE(e.find("edited.ini"), std::string::npos) << e;
  }
}

TEST(PlaceCellsIni, UnknownKeyIsAnError) {
  std::string text = ConfigText({});
  text = Edit(text, "measure", "keep_min", "8\nkeep_maximum = 3");
  try {
    PlaceCellsConfig::FromIni(glue::IniFile::Parse(text, "typo.ini"), "");
    FAIL() << "no error";
  } catch (const glue::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("[measure] keep_maximum"), std::string::npos) << e.what();
  }
}

TEST(PlaceMemoryFile, RoundTripThroughAFileKeepsCellsPosesAndDescriptors) {
  const auto memory = ThreeCellMemory();
  const std::string dir = TempDir("roundtrip");
  const std::string path = dir + "/cells.mem";
  glue::SavePlaceMemory(memory, path);
  // The save went through a temporary file that is gone now.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1);

  const auto loaded = glue::LoadPlaceMemory(path);
  ASSERT_EQ(loaded.size(), memory.size());
  EXPECT_EQ(loaded.view_options().features.method, memory.view_options().features.method);
  EXPECT_EQ(loaded.view_options().window_px, memory.view_options().window_px);
  EXPECT_EQ(loaded.view_options().vline.window_px, memory.view_options().vline.window_px);
  EXPECT_EQ(loaded.panorama().width_px, memory.panorama().width_px);
  EXPECT_EQ(loaded.panorama().elevation_top_rad, memory.panorama().elevation_top_rad);
  for (int i = 0; i < memory.size(); ++i) {
    const auto& a = memory.cell(i);
    const auto& b = loaded.cell(i);
    EXPECT_EQ(a.id, b.id);
    EXPECT_EQ(a.utime, b.utime);
    EXPECT_EQ(a.pose.x_m, b.pose.x_m);
    EXPECT_EQ(a.pose.y_m, b.pose.y_m);
    EXPECT_EQ(a.pose.theta_rad, b.pose.theta_rad);
    EXPECT_GT(a.view.landmarks.size(), 20) << "cell " << i << " has few landmarks: a weak test";
    ExpectSameSet(a.view.landmarks, b.view.landmarks, "landmarks of cell " + std::to_string(i));
    ExpectSameSet(a.view.vlines, b.view.vlines, "lines of cell " + std::to_string(i));
    EXPECT_TRUE(SameMat(a.view.windows, b.view.windows)) << "windows of cell " << i;
    EXPECT_TRUE(SameMat(a.view.signature, b.view.signature)) << "signature of cell " << i;
  }
  // Saved again, byte for byte the same file; a new cell gets the same id in both.
  const std::string again = dir + "/again.mem";
  glue::SavePlaceMemory(loaded, again);
  EXPECT_EQ(ReadBytes(path), ReadBytes(again));
  auto a = memory;
  auto b = loaded;
  const auto config = Config("", {});
  const auto view = nav::MakePlaceView(Indoor13::Get().Panorama({3.0, 3.0, 0.5}), config.view);
  EXPECT_EQ(a.cell(a.Add({3, 3, 0.5}, 9, view)).id, b.cell(b.Add({3, 3, 0.5}, 9, view)).id);
}

TEST(PlaceMemoryFile, SaveReplacesAnExistingFile) {
  const std::string path = TempDir("replace") + "/cells.mem";
  WriteBytes(path, {1, 2, 3});
  const auto memory = ThreeCellMemory();
  glue::SavePlaceMemory(memory, path);
  EXPECT_EQ(glue::LoadPlaceMemory(path).size(), 3);
}

TEST(PlaceMemoryFile, SaveIntoAMissingFolderNamesTheFile) {
  const std::string path = TempDir("nofolder") + "/no/such/folder/cells.mem";
  try {
    glue::SavePlaceMemory(ThreeCellMemory(), path);
    FAIL() << "no error";
  } catch (const glue::PlaceMemoryError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(PlaceMemoryFile, MissingFileIsNamed) {
  const std::string path = TempDir("missing") + "/none.mem";
  try {
    glue::LoadPlaceMemory(path);
    FAIL() << "no error";
  } catch (const glue::PlaceMemoryError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot open"), std::string::npos) << e.what();
  }
}

// The message of loading `bytes` from a file; fails the test when it loads.
std::string LoadError(const std::string& path, const std::vector<uint8_t>& bytes) {
  WriteBytes(path, bytes);
  try {
    glue::LoadPlaceMemory(path);
  } catch (const glue::PlaceMemoryError& e) {
    return e.what();
  }
  ADD_FAILURE() << "loaded " << bytes.size() << " bytes";
  return "";
}

// The byte offset the message names ("at byte N"), -1 when none.
long OffsetIn(const std::string& message) {
  const auto at = message.rfind("at byte ");
  if (at == std::string::npos) return -1;
  return std::stol(message.substr(at + 8));
}

TEST(PlaceMemoryFile, TruncatedFilesAreRefusedNamingFileAndOffset) {
  const auto bytes = ThreeCellMemory().Serialize();
  const std::string path = TempDir("truncated") + "/cells.mem";
  for (const size_t size : {size_t{0}, size_t{10}, size_t{18}, size_t{20}, size_t{40}, size_t{100}, bytes.size() / 3,
                            bytes.size() / 2, bytes.size() - 9, bytes.size() - 1}) {
    const std::string e = LoadError(path, std::vector<uint8_t>(bytes.begin(), bytes.begin() + size));
    EXPECT_NE(e.find(path), std::string::npos) << size << ": " << e;
    const long offset = OffsetIn(e);
    EXPECT_GE(offset, 0) << size << ": " << e;
    EXPECT_LE(offset, static_cast<long>(size)) << size << ": " << e;
  }
}

TEST(PlaceMemoryFile, ForeignMagicWrongVersionAndCorruptionAreRefused) {
  const auto bytes = ThreeCellMemory().Serialize();
  const std::string path = TempDir("corrupt") + "/cells.mem";
  auto magic = bytes;
  magic[3] ^= 0x20;
  std::string e = LoadError(path, magic);
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_NE(e.find("magic"), std::string::npos) << e;
  EXPECT_EQ(OffsetIn(e), 0) << e;

  auto version = bytes;
  version[18] = 99;  // the u32 after the 18-byte magic
  e = LoadError(path, version);
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_NE(e.find("version 99"), std::string::npos) << e;
  EXPECT_EQ(OffsetIn(e), 18) << e;

  auto flipped = bytes;
  flipped[bytes.size() / 2] ^= 0x01;
  e = LoadError(path, flipped);
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_GE(OffsetIn(e), 0) << e;

  // A text file, an image: foreign.
  const std::string text = "[channels]\nomni = OMNI_FRAME\n";
  e = LoadError(path, std::vector<uint8_t>(text.begin(), text.end()));
  EXPECT_NE(e.find(path), std::string::npos) << e;
  EXPECT_EQ(OffsetIn(e), 0) << e;
}

TEST(PlaceCellMessages, LocalizationToMatchAndPose) {
  nav::Localization loc;
  loc.cell = 2;
  loc.cell_id = 7;
  loc.pose = {1.5, -2.0, 0.25};
  loc.covariance << 0.01, 0.002, 0.003, 0.002, 0.02, 0.004, 0.003, 0.004, 0.05;
  loc.best.distance = 0.12;
  loc.best.score = 0.3;
  loc.candidates = 9;
  nav::PlaceCell cell;
  cell.id = 7;
  cell.pose = {1.4, -2.1, 0.1};
  const auto m = glue::ToPlaceCellMatchMsg(123, loc, cell, nav::PlaceMeasure::kMatchCount);
  EXPECT_EQ(m.utime, 123);
  EXPECT_EQ(m.cell_id, 7);
  EXPECT_EQ(m.distance_measure, place_cell_match_t::MATCH_COUNT);
  EXPECT_FLOAT_EQ(m.distance, 0.12f);
  EXPECT_FLOAT_EQ(m.score, 0.3f);
  EXPECT_EQ(m.ncandidates, 9);
  EXPECT_EQ(m.x_m, 1.4);  // the cell's position, not the estimate
  EXPECT_EQ(m.y_m, -2.1);
  EXPECT_EQ(m.theta_rad, 0.1);
  EXPECT_EQ(static_cast<int>(nav::PlaceMeasure::kBearingDifference), place_cell_match_t::BEARING_DIFFERENCE);
  EXPECT_EQ(static_cast<int>(nav::PlaceMeasure::kVlineTemplate), place_cell_match_t::VLINE_TEMPLATE);

  cell.id = 8;
  EXPECT_THROW(glue::ToPlaceCellMatchMsg(123, loc, cell, nav::PlaceMeasure::kMatchCount), std::invalid_argument);

  const auto none = glue::NoPlaceCellMatchMsg(124, nav::PlaceMeasure::kBearingDifference, 4);
  EXPECT_EQ(none.cell_id, -1);
  EXPECT_EQ(none.ncandidates, 4);
  EXPECT_EQ(none.utime, 124);

  const auto p = glue::ToPlaceCellPoseMsg(125, loc);
  EXPECT_EQ(p.utime, 125);
  EXPECT_EQ(p.estimator, "place_cells");
  EXPECT_EQ(p.frame, "map");
  EXPECT_EQ(p.x_m, 1.5);
  EXPECT_EQ(p.y_m, -2.0);
  EXPECT_EQ(p.theta_rad, 0.25);
  EXPECT_EQ(p.covariance[1], 0.002);  // (0, 1)
  EXPECT_EQ(p.covariance[5], 0.004);  // (1, 2): row-major
  EXPECT_EQ(p.covariance[6], 0.003);  // (2, 0)
  EXPECT_EQ(p.covariance[8], 0.05);
}

// Every number of the shipped placecells.ini made negative or NaN: each error names the file, the line
// and the key.
TEST(PlaceCellsConfigFile, EveryRefusedNumberNamesFileLineAndKey) {
  EXPECT_GT(test_support::ExpectBadNumbersNamed(SNAPNAV_CONFIG_DIR "/placecells.ini",
                                                [](const glue::IniFile& ini) { PlaceCellsConfig::FromIni(ini, ""); }),
            0);
}

}  // namespace
}  // namespace snapnav::processes::test
