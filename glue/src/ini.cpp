#include "snapnav/glue/ini.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "snapnav/glue/flags.hpp"

namespace snapnav::glue {
namespace {

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

}  // namespace

IniFile IniFile::Load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError("cannot open config file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return Parse(ss.str(), path);
}

IniFile IniFile::Parse(const std::string& text, const std::string& origin) {
  IniFile ini;
  ini.origin_ = origin;
  std::istringstream in(text);
  std::string line;
  std::string section;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    std::string t = Trim(line);
    if (t.empty() || t[0] == '#' || t[0] == ';') continue;
    const std::string where = origin + ":" + std::to_string(lineno);
    if (t[0] == '[') {
      if (t.back() != ']') throw ConfigError(where + ": malformed section header '" + t + "'");
      section = Trim(t.substr(1, t.size() - 2));
      if (section.empty()) throw ConfigError(where + ": empty section name");
      ini.sections_[section];
      ini.section_lines_.emplace(section, lineno);
      continue;
    }
    const auto eq = t.find('=');
    if (eq == std::string::npos) throw ConfigError(where + ": expected 'key = value', got '" + t + "'");
    if (section.empty()) throw ConfigError(where + ": key outside of any [section]");
    const std::string key = Trim(t.substr(0, eq));
    std::string value = Trim(t.substr(eq + 1));
    // Trailing comments start with " #" or " ;"; an empty value may be followed by one (`key = ; note`).
    if (!value.empty() && (value[0] == '#' || value[0] == ';')) value.clear();
    for (const char* c : {" #", " ;", "\t#", "\t;"}) {
      if (const auto p = value.find(c); p != std::string::npos) value = Trim(value.substr(0, p));
    }
    if (key.empty()) throw ConfigError(where + ": empty key");
    auto& entries = ini.sections_[section];
    if (entries.count(key)) {
      throw ConfigError(where + ": key '" + key + "' repeated in [" + section + "] (first on line " +
                        std::to_string(entries[key].line) + ")");
    }
    entries[key] = Entry{value, lineno};
  }
  return ini;
}

bool IniFile::Has(const std::string& section, const std::string& key) const {
  const auto s = sections_.find(section);
  return s != sections_.end() && s->second.count(key) > 0;
}

std::vector<std::string> IniFile::Sections() const {
  std::vector<std::string> out;
  for (const auto& [name, _] : sections_) out.push_back(name);
  return out;
}

std::vector<std::string> IniFile::SectionsInFileOrder() const {
  std::vector<std::pair<int, std::string>> by_line;
  for (const auto& [name, line] : section_lines_) by_line.emplace_back(line, name);
  std::sort(by_line.begin(), by_line.end());
  std::vector<std::string> out;
  for (const auto& [_, name] : by_line) out.push_back(name);
  return out;
}

int IniFile::SectionLine(const std::string& section) const {
  const auto s = section_lines_.find(section);
  return s == section_lines_.end() ? 0 : s->second;
}

std::vector<std::string> IniFile::Keys(const std::string& section) const {
  std::vector<std::string> out;
  if (const auto s = sections_.find(section); s != sections_.end()) {
    for (const auto& [key, _] : s->second) out.push_back(key);
  }
  return out;
}

int IniFile::KeyLine(const std::string& section, const std::string& key) const {
  const auto s = sections_.find(section);
  if (s == sections_.end()) return 0;
  const auto k = s->second.find(key);
  return k == s->second.end() ? 0 : k->second.line;
}

void IniFile::Set(const std::string& section, const std::string& key, const std::string& value,
                  const std::string& origin) {
  const auto s = sections_.find(section);
  if (s == sections_.end() || !s->second.count(key)) {
    throw ConfigError(origin + ": " + origin_ + " has no key '" + key + "' in section [" + section + "]");
  }
  s->second[key].value = value;
}

const IniFile::Entry& IniFile::Find(const std::string& section, const std::string& key) const {
  const auto s = sections_.find(section);
  if (s == sections_.end()) throw ConfigError(origin_ + ": missing section [" + section + "] (needed for key '" + key + "')");
  const auto k = s->second.find(key);
  if (k == s->second.end()) throw ConfigError(origin_ + ": missing key '" + key + "' in section [" + section + "]");
  used_.insert({section, key});
  return k->second;
}

void IniFile::Fail(const Entry& e, const std::string& section, const std::string& key, const std::string& why) const {
  throw ConfigError(origin_ + ":" + std::to_string(e.line) + ": [" + section + "] " + key + " = '" + e.value + "': " + why);
}

std::string IniFile::GetString(const std::string& section, const std::string& key) const {
  return Find(section, key).value;
}

double IniFile::GetDouble(const std::string& section, const std::string& key) const {
  const Entry& e = Find(section, key);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(e.value.c_str(), &end);
  if (e.value.empty() || *end != '\0' || errno == ERANGE) Fail(e, section, key, "expected a number");
  return v;
}

int IniFile::GetInt(const std::string& section, const std::string& key) const {
  const Entry& e = Find(section, key);
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(e.value.c_str(), &end, 10);
  if (e.value.empty() || *end != '\0' || errno == ERANGE || v < INT32_MIN || v > INT32_MAX) {
    Fail(e, section, key, "expected an integer");
  }
  return static_cast<int>(v);
}

bool IniFile::GetBool(const std::string& section, const std::string& key) const {
  const Entry& e = Find(section, key);
  if (e.value == "true" || e.value == "1" || e.value == "yes" || e.value == "on") return true;
  if (e.value == "false" || e.value == "0" || e.value == "no" || e.value == "off") return false;
  Fail(e, section, key, "expected true or false");
}

std::vector<double> IniFile::GetDoubleList(const std::string& section, const std::string& key) const {
  const Entry& e = Find(section, key);
  std::vector<double> out;
  for (const auto& part : SplitList(e.value)) {
    char* end = nullptr;
    const double v = std::strtod(part.c_str(), &end);
    if (part.empty() || *end != '\0') Fail(e, section, key, "expected a comma-separated list of numbers");
    out.push_back(v);
  }
  return out;
}

void IniFile::CheckAllUsed() const {
  std::string unknown;
  for (const auto& [section, entries] : sections_) {
    for (const auto& [key, e] : entries) {
      if (!used_.count({section, key})) {
        unknown += "\n  " + origin_ + ":" + std::to_string(e.line) + ": [" + section + "] " + key;
      }
    }
  }
  if (!unknown.empty()) throw ConfigError("unknown config keys (typo, or not an option of this program):" + unknown);
}

}  // namespace snapnav::glue
