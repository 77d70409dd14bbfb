#pragma once
// Config errors name the file, the line and the key: for every key of a config file whose value is
// a number, the file with that value replaced by each of `bad_values` is given to `read` (a
// component's config reader); when the reader refuses it, the error must name "FILE:LINE" of that
// key and the key. A reader that accepts the value passes (a negative value may be allowed).
//   ExpectBadNumbersNamed(path, [](const glue::IniFile& ini) { XConfig::FromIni(ini, ""); });

#include <gtest/gtest.h>

#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "snapnav/glue/ini.hpp"

namespace snapnav::test_support {

inline bool IsNumber(const std::string& text) {
  char* end = nullptr;
  std::strtod(text.c_str(), &end);
  return !text.empty() && *end == '\0';
}

// Returns how many of the tried values the reader refused.
template <class Read>
int ExpectBadNumbersNamed(const std::string& path, Read&& read,
                          const std::vector<std::string>& bad_values = {"-1", "nan"}) {
  const glue::IniFile original = glue::IniFile::Load(path);
  int refused = 0;
  for (const auto& section : original.Sections()) {
    for (const auto& key : original.Keys(section)) {
      if (!IsNumber(original.GetString(section, key))) continue;
      // "FILE:LINE: [section] key = ..." or, for the second key a message names, "FILE:... (line LINE: key ...".
      const std::string line = std::to_string(original.KeyLine(section, key));
      const std::string where = path + ":" + line + ": ";
      for (const auto& value : bad_values) {
        glue::IniFile ini = glue::IniFile::Load(path);
        ini.Set(section, key, value, "test");
        try {
          read(ini);
        } catch (const std::exception& e) {
          ++refused;
          const std::string what = e.what();
          const bool located =
              what.find(where) != std::string::npos ||
              (what.find(path + ":") != std::string::npos && what.find("line " + line + ": ") != std::string::npos);
          EXPECT_TRUE(located) << "[" << section << "] " << key << " = " << value << ": the error does not name "
                               << where << "\n  " << what;
          EXPECT_NE(what.find(key), std::string::npos)
              << "[" << section << "] " << key << " = " << value << ": the error does not name the key\n  " << what;
        }
      }
    }
  }
  return refused;
}

}  // namespace snapnav::test_support
