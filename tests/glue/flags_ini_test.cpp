#include <gtest/gtest.h>

#include <functional>
#include <sstream>
#include <stdexcept>

#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"
#include "snapnav/glue/suggest.hpp"

namespace snapnav::glue {
namespace {

TEST(Flags, ParsesBothFormsAndCommonFlags) {
  CommonFlags common;
  int n = 1;
  double rate = 2;
  bool verbose = false;
  Flags flags("prog", "test");
  flags.AddCommon(&common);
  flags.AddInt("count", &n, "n");
  flags.AddDouble("rate-hz", &rate, "r");
  flags.AddBool("verbose", &verbose, "v");
  const char* argv[] = {"prog", "--count", "5", "--rate-hz=7.5", "--verbose", "--lcm-url", "memq://",
                        "--channel-prefix=RUN1_"};
  std::ostringstream out;
  ASSERT_TRUE(flags.Parse(8, argv, out));
  EXPECT_EQ(n, 5);
  EXPECT_DOUBLE_EQ(rate, 7.5);
  EXPECT_TRUE(verbose);
  EXPECT_EQ(common.lcm_url, "memq://");
  EXPECT_EQ(common.channel_prefix, "RUN1_");
}

TEST(Flags, HelpListsEveryFlag) {
  CommonFlags common;
  Flags flags("prog", "does things");
  flags.AddCommon(&common);
  const char* argv[] = {"prog", "--help"};
  std::ostringstream out;
  EXPECT_FALSE(flags.Parse(2, argv, out));
  for (const char* f : {"--config", "--lcm-url", "--channel-prefix", "--help", "does things"}) {
    EXPECT_NE(out.str().find(f), std::string::npos) << f;
  }
}

TEST(Flags, BadInputIsAnError) {
  int n = 0;
  Flags flags("prog", "t");
  flags.AddInt("count", &n, "n");
  std::ostringstream out;
  const char* unknown[] = {"prog", "--cuont", "3"};
  EXPECT_THROW(flags.Parse(3, unknown, out), FlagError);
  const char* missing[] = {"prog", "--count"};
  EXPECT_THROW(flags.Parse(2, missing, out), FlagError);
  const char* bad[] = {"prog", "--count", "3x"};
  EXPECT_THROW(flags.Parse(3, bad, out), FlagError);
  const char* positional[] = {"prog", "stray"};
  EXPECT_THROW(flags.Parse(2, positional, out), FlagError);
}

TEST(Ini, ReadsTypedValuesWithComments) {
  const auto ini = IniFile::Parse(
      "# comment\n[a]\nx = 1.5 ; metres\nn = 3\nflag = true\nlist = 1, 2,3\n[b]\nname = HELLO # trailing\n", "t.ini");
  EXPECT_DOUBLE_EQ(ini.GetDouble("a", "x"), 1.5);
  EXPECT_EQ(ini.GetInt("a", "n"), 3);
  EXPECT_TRUE(ini.GetBool("a", "flag"));
  EXPECT_EQ(ini.GetDoubleList("a", "list"), (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(ini.GetString("b", "name"), "HELLO");
  EXPECT_NO_THROW(ini.CheckAllUsed());
  // An empty value with a comment after it.
  const auto empty = IniFile::Parse("[a]\nmask =            ; none\nother = # none either\nbare =\n", "e.ini");
  EXPECT_EQ(empty.GetString("a", "mask"), "");
  EXPECT_EQ(empty.GetString("a", "other"), "");
  EXPECT_EQ(empty.GetString("a", "bare"), "");
}

TEST(Ini, MissingKeyNamesSectionAndKey) {
  const auto ini = IniFile::Parse("[a]\nx = 1\n", "cfg.ini");
  try {
    ini.GetDouble("a", "y");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("missing key 'y' in section [a]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cfg.ini"), std::string::npos);
  }
}

TEST(Ini, UnknownKeyAndBadValueNameTheLine) {
  const auto ini = IniFile::Parse("[a]\nx = 1\nxx = 2\nn = abc\n", "cfg.ini");
  ini.GetDouble("a", "x");
  try {
    ini.GetInt("a", "n");
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cfg.ini:4"), std::string::npos) << e.what();
  }
  try {
    ini.CheckAllUsed();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("cfg.ini:3: [a] xx"), std::string::npos) << e.what();
  }
}

TEST(Ini, SyntaxErrorsNameTheLine) {
  EXPECT_THROW(IniFile::Parse("[a\n", "f"), ConfigError);
  EXPECT_THROW(IniFile::Parse("x = 1\n", "f"), ConfigError);
  EXPECT_THROW(IniFile::Parse("[a]\nnovalue\n", "f"), ConfigError);
  EXPECT_THROW(IniFile::Parse("[a]\nx = 1\nx = 2\n", "f"), ConfigError);
  EXPECT_THROW(IniFile::Load("/nonexistent.ini"), ConfigError);
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Suggest, NearestNameWithinAThirdOfTheName) {
  EXPECT_EQ(EditDistance("translation", "translaton"), 1);
  EXPECT_EQ(EditDistance("ttl", "tlt"), 1);  // a transposition is one edit
  EXPECT_EQ(NearestName("tranlation_noise_m_per_m", {"rotation_noise_rad_per_m", "translation_noise_m_per_m"}),
            "translation_noise_m_per_m");
  EXPECT_EQ(NearestName("x", {"y"}), "");  // one-letter names are all one edit apart
  EXPECT_EQ(NearestName("ttl", {"tll"}), "tll");
  EXPECT_EQ(NearestName("seed", {"speed_mps", "depth"}), "");
  EXPECT_EQ(NearestName("depth", {"depth"}), "");
  EXPECT_EQ(DidYouMean("--cuont", {"--count"}), " (did you mean '--count'?)");
}

// A missing key names the line of its section, and a key of the section nobody read that looks like
// a typo of it (it named neither).
TEST(Ini, MissingKeyNamesTheSectionLineAndATypoOfIt) {
  const auto ini = IniFile::Parse("# c\n[a]\nx = 1\nrotation_noise_rad_per_mm = 2\n[camera]\nz = 1\n", "cfg.ini");
  ini.GetDouble("a", "x");
  EXPECT_EQ(
      ErrorOf([&] { ini.GetDouble("a", "rotation_noise_rad_per_m"); }),
      "cfg.ini:2: missing key 'rotation_noise_rad_per_m' in section [a] (the section begins on this line); line 4 "
      "has 'rotation_noise_rad_per_mm': a typo of it?");
  EXPECT_EQ(
      ErrorOf([&] { ini.GetDouble("camera", "x"); }),
      "cfg.ini:5: missing key 'x' in section [camera] (the section begins on this line); line 3 has it in [a]: in "
      "the wrong section?");
  EXPECT_EQ(ErrorOf([&] { ini.GetDouble("camrea", "z"); }),
            "cfg.ini: missing section [camrea] (needed for key 'z'); line 5 has [camera]: a typo of it?");
}

// A key nobody read: its line, and the nearest key the program reads (in its section, or the section
// it belongs in, or the nearest section).
TEST(Ini, UnknownKeySuggestsTheNearestKnownOne) {
  const auto ini = IniFile::Parse(
      "[a]\ntranslation_noise_m_per_m = 1\ntranlation_noise_m_per_m = 2\nz = 3\n[camera]\ny = 1\nz = 2\n[camrea]\nq = "
      "1\n",
      "cfg.ini");
  ini.GetDouble("a", "translation_noise_m_per_m");
  ini.GetDouble("camera", "y");
  ini.GetDouble("camera", "z");
  const std::string e = ErrorOf([&] { ini.CheckAllUsed(); });
  EXPECT_NE(e.find("cfg.ini:3: [a] tranlation_noise_m_per_m (did you mean 'translation_noise_m_per_m'?)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("cfg.ini:4: [a] z (a key of [camera], not of [a])"), std::string::npos) << e;
  EXPECT_NE(e.find("cfg.ini:9: [camrea] q (this program reads no [camrea]; did you mean [camera]?)"), std::string::npos)
      << e;
}

// A value the options' own check refuses: the keys its message names, with their lines and values.
TEST(Ini, ValidationErrorNamesTheKeysItsMessageNames) {
  const auto ini = IniFile::Parse("[s]\nalpha_m = -1\nbeta_m = 2\n[t]\nbeta_m = 3\n", "v.ini");
  ini.GetDouble("s", "alpha_m");
  ini.GetDouble("s", "beta_m");
  ini.GetDouble("t", "beta_m");
  EXPECT_EQ(std::string(ini.ValidationError("thing: alpha_m must be >= 0").what()),
            "v.ini:2: [s] alpha_m = '-1': thing: alpha_m must be >= 0");
  EXPECT_EQ(std::string(ini.ValidationError("[t] beta_m must exceed 5").what()),
            "v.ini:5: [t] beta_m = '3': [t] beta_m must exceed 5");
  EXPECT_EQ(std::string(ini.ValidationError("thing: beta_m must exceed alpha_m").what()),
            "v.ini:2: [s] alpha_m = '-1' (line 3: beta_m = '2', line 5: [t] beta_m = '3'): thing: beta_m must exceed "
            "alpha_m");
  // A key that is a plain word counts only when no key with a '_' is named, a channel only with [channels].
  const auto words = IniFile::Parse("[channels]\nmap = MAP\n[slam]\nmap_drift_m = -1\nbins = 1\n", "w.ini");
  words.GetString("channels", "map");
  words.GetDouble("slam", "map_drift_m");
  words.GetDouble("slam", "bins");
  EXPECT_EQ(std::string(words.ValidationError("slam: the map drift map_drift_m must be >= 0, bins >= 2").what()),
            "w.ini:4: [slam] map_drift_m = '-1': slam: the map drift map_drift_m must be >= 0, bins >= 2");
  EXPECT_EQ(std::string(words.ValidationError("slam: bins must be >= 2 for the map").what()),
            "w.ini:5: [slam] bins = '1': slam: bins must be >= 2 for the map");
  EXPECT_EQ(std::string(words.ValidationError("[channels] map is empty").what()),
            "w.ini:2: [channels] map = 'MAP': [channels] map is empty");
  EXPECT_EQ(std::string(ini.ValidationError("thing: no key named").what()), "v.ini: thing: no key named");
  // An option named otherwise than its key: a word the key ends with, or that ends with the key.
  const auto effects = IniFile::Parse("[effects]\nillumination_gain = -1\n[robot]\nradius_m = 0\n", "e.ini");
  effects.GetDouble("effects", "illumination_gain");
  effects.GetDouble("robot", "radius_m");
  EXPECT_EQ(std::string(effects.ValidationError("image effects: gain must be >= 0").what()),
            "e.ini:2: [effects] illumination_gain = '-1': image effects: gain must be >= 0");
  EXPECT_EQ(std::string(effects.ValidationError("drive: robot_radius_m must be positive").what()),
            "e.ini:4: [robot] radius_m = '0': drive: robot_radius_m must be positive");
  EXPECT_EQ(std::string(effects.ValidationError("drive: too far, 3 m").what()), "e.ini: drive: too far, 3 m");
  // Of the keys matched so, those sharing the longest tail with a word: `loop_search_sigmas` is
  // graph_loop_search_sigmas (18 characters shared), not search_sigmas (13).
  const auto tails = IniFile::Parse("[slam]\nsearch_sigmas = 3\ngraph_loop_search_sigmas = -1\n", "t.ini");
  tails.GetDouble("slam", "search_sigmas");
  tails.GetDouble("slam", "graph_loop_search_sigmas");
  EXPECT_EQ(std::string(tails.ValidationError("graph: loop_search_sigmas must be > 0").what()),
            "t.ini:3: [slam] graph_loop_search_sigmas = '-1': graph: loop_search_sigmas must be > 0");
  // An option in radians names its key in degrees.
  const auto angles = IniFile::Parse("[follower]\nalign_deg = -5\nmax_angular_deg_per_s = 0\n", "a.ini");
  angles.GetDouble("follower", "align_deg");
  angles.GetDouble("follower", "max_angular_deg_per_s");
  EXPECT_EQ(std::string(angles.ValidationError("follower: align_rad must be positive").what()),
            "a.ini:2: [follower] align_deg = '-5': follower: align_rad must be positive");
  EXPECT_EQ(std::string(angles.ValidationError("follower: max_angular_radps must be positive").what()),
            "a.ini:3: [follower] max_angular_deg_per_s = '0': follower: max_angular_radps must be positive");
  EXPECT_EQ(ErrorOf([&] { ini.Check([] { throw std::invalid_argument("alpha_m must be >= 0"); }); }),
            "v.ini:2: [s] alpha_m = '-1': alpha_m must be >= 0");
  EXPECT_EQ(ErrorOf([&] { ini.FailKey("s", "beta_m", "too big"); }), "v.ini:3: [s] beta_m = '2': too big");
  EXPECT_EQ(ErrorOf([&] { ini.FailKey("t", "gamma", "needed"); }), "v.ini:4: [t] gamma: needed");
}

TEST(Ini, OverrideOfAMissingKeySuggestsTheNearest) {
  auto ini = IniFile::Parse("[homing]\nhome = first\n", "h.ini");
  EXPECT_EQ(ErrorOf([&] { ini.Set("homing", "hom", "image", "--set homing:homing.hom"); }),
            "--set homing:homing.hom: h.ini has no key 'hom' in section [homing] (did you mean 'home'?)");
  EXPECT_EQ(ErrorOf([&] { ini.Set("homin", "home", "image", "--set homing:homin.home"); }),
            "--set homing:homin.home: h.ini has no section [homin] (did you mean [homing]?)");
}

// The usage line names the positional arguments once; a list flag says "(repeatable)" once; a help
// that says what the default is gets no second one; an unknown flag suggests the nearest.
TEST(Flags, UsageShowsEachPartOnce) {
  std::vector<std::string> sets;
  int seed = -1, count = 3;
  std::string host = "vm";
  Flags flags("launch DEPLOYMENT [NAME=VALUE...]", "runs things");
  flags.AddStringList("set", &sets, "override KEY=VALUE (repeatable)");
  flags.AddInt("seed", &seed, "random seed (default: the config's)");
  flags.AddInt("count", &count, "how many");
  flags.AddString("host", &host, "this machine", "this machine's hostname");
  flags.AllowPositional("DEPLOYMENT [NAME=VALUE...]", "the file, then variables");
  std::ostringstream out;
  flags.PrintUsage(out);
  const std::string text = out.str();
  EXPECT_EQ(text.substr(0, text.find('\n')), "usage: launch [flags] DEPLOYMENT [NAME=VALUE...]");
  EXPECT_NE(text.find("override KEY=VALUE (repeatable)\n"), std::string::npos) << text;
  EXPECT_NE(text.find("random seed (default: the config's)\n"), std::string::npos) << text;
  EXPECT_EQ(text.find("(default: -1)"), std::string::npos) << text;
  EXPECT_NE(text.find("how many (default: 3)"), std::string::npos) << text;
  EXPECT_NE(text.find("this machine (default: this machine's hostname)"), std::string::npos) << text;
  EXPECT_EQ(text.find("(default: vm)"), std::string::npos) << text;

  Flags positional_in_name("log-report LOG", "s");
  std::ostringstream out2;
  positional_in_name.PrintUsage(out2);
  EXPECT_EQ(out2.str().substr(0, out2.str().find('\n')), "usage: log-report [flags] LOG");

  const char* typo[] = {"launch", "--cuont", "3"};
  EXPECT_EQ(ErrorOf([&] { flags.Parse(3, typo, out); }), "unknown flag --cuont (did you mean --count?) (see --help)");
}

}  // namespace
}  // namespace snapnav::glue
