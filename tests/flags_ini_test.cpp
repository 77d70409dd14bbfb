#include <gtest/gtest.h>

#include <sstream>

#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"

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

}  // namespace
}  // namespace snapnav::glue
