#pragma once
// INI configuration: one section per concern, `key = value`, `#` or `;` comments.
// Every error names the file, the line, the section and the key: a missing key (with the
// section's line, and the file's nearest key when it looks like a typo of it), a malformed
// value, a key nobody asked for (with the nearest known key: "did you mean X?") and a value
// the options' own check rejects (ValidationError, Check).

#include <initializer_list>
#include <iosfwd>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace snapnav::glue {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class IniFile {
 public:
  static IniFile Load(const std::string& path);
  static IniFile Parse(const std::string& text, const std::string& origin);

  const std::string& origin() const { return origin_; }
  bool Has(const std::string& section, const std::string& key) const;
  std::vector<std::string> Sections() const;
  // Sections in the order their headers first appear; the header's line (0: no such section).
  std::vector<std::string> SectionsInFileOrder() const;
  int SectionLine(const std::string& section) const;
  // The keys of a section (sorted) and the line of a key (0: no such key); neither marks a key used.
  std::vector<std::string> Keys(const std::string& section) const;
  int KeyLine(const std::string& section, const std::string& key) const;

  // Replaces the value of an existing key (a command-line override; `origin` names it in
  // errors). A key the file does not have is a ConfigError: an override cannot add options.
  void Set(const std::string& section, const std::string& key, const std::string& value, const std::string& origin);

  // Getters mark the key as used; a missing key or a bad value throws ConfigError.
  std::string GetString(const std::string& section, const std::string& key) const;
  double GetDouble(const std::string& section, const std::string& key) const;
  int GetInt(const std::string& section, const std::string& key) const;
  bool GetBool(const std::string& section, const std::string& key) const;
  std::vector<double> GetDoubleList(const std::string& section, const std::string& key) const;

  // Throws ConfigError listing every key that was never read (a typo, or an option this
  // version does not have), each with its line and the nearest key that was read ("did you
  // mean X?").
  void CheckAllUsed() const;

  // Throws "ORIGIN:LINE: [section] key = 'value': why" (the section's line when the file lacks
  // the key). For a value that reads but is not acceptable (out of range, inconsistent).
  [[noreturn]] void FailKey(const std::string& section, const std::string& key, const std::string& why) const;

  // The error for `what`, a complaint about options read from this file (an options struct's
  // Validate() message): it names the file, and the line, section and value of each key that
  // was read from it and that `what` names as a word ("laser slam: icp_iterations must be >= 1"
  // -> "laser_slam.ini:31: [laser_slam] icp_iterations = '0': laser slam: icp_iterations must be
  // >= 1"), or else whose name ends with a word of it or is the end of one at a '_' (the option
  // `gain` of the key `illumination_gain`). A message naming no key read from the file gets the
  // file only.
  ConfigError ValidationError(const std::string& what) const;

  // Runs `check` (e.g. [&] { options.Validate(); }) and turns the std::invalid_argument it
  // throws into ValidationError.
  template <class F>
  void Check(F&& check) const {
    try {
      check();
    } catch (const std::invalid_argument& e) {
      throw ValidationError(e.what());
    }
  }

 private:
  struct Entry {
    std::string value;
    int line = 0;
  };
  const Entry& Find(const std::string& section, const std::string& key) const;
  [[noreturn]] void Fail(const Entry& e, const std::string& section, const std::string& key,
                         const std::string& why) const;

  std::string origin_;
  std::map<std::string, std::map<std::string, Entry>> sections_;
  std::map<std::string, int> section_lines_;  // first header line of each section
  mutable std::set<std::pair<std::string, std::string>> used_;
};

// The value of [section] key as one of `choices` (name, value); anything else is a ConfigError
// listing the choices.
template <class E>
E ReadChoice(const IniFile& ini, const std::string& section, const std::string& key,
             std::initializer_list<std::pair<const char*, E>> choices) {
  const std::string value = ini.GetString(section, key);
  std::string names;
  for (const auto& [name, e] : choices) {
    if (value == name) return e;
    names += names.empty() ? name : std::string(" | ") + name;
  }
  ini.FailKey(section, key, "expected " + names);
}

}  // namespace snapnav::glue
