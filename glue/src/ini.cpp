#include "snapnav/glue/ini.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/suggest.hpp"

namespace snapnav::glue {
namespace {

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

// An option's name with its angles in degrees: options hold radians where their config keys say
// degrees ("align_rad" is the key "align_deg", "max_angular_radps" is "max_angular_deg_per_s").
std::string InDegrees(const std::string& name) {
  std::string out, part;
  std::istringstream in(name);
  while (std::getline(in, part, '_')) {
    if (part == "rad") part = "deg";
    if (part == "radps") part = "deg_per_s";
    out += (out.empty() ? "" : "_") + part;
  }
  return out;
}

// The words of `text`: runs of letters, digits and '_', each also in degrees (InDegrees).
std::set<std::string> Words(const std::string& text) {
  std::set<std::string> words;
  std::string cur;
  for (const char c : text + " ") {
    if (std::isalnum(static_cast<unsigned char>(c)) || c == '_') {
      cur += c;
    } else if (!cur.empty()) {
      words.insert(cur);
      words.insert(InDegrees(cur));
      cur.clear();
    }
  }
  return words;
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
  if (s == sections_.end()) {
    throw ConfigError(origin + ": " + origin_ + " has no section [" + section + "]" +
                      DidYouMean(section, Sections(), "[", "]"));
  }
  if (!s->second.count(key)) {
    throw ConfigError(origin + ": " + origin_ + " has no key '" + key + "' in section [" + section + "]" +
                      DidYouMean(key, Keys(section)));
  }
  s->second[key].value = value;
}

const IniFile::Entry& IniFile::Find(const std::string& section, const std::string& key) const {
  const auto s = sections_.find(section);
  if (s == sections_.end()) {
    std::string text = origin_ + ": missing section [" + section + "] (needed for key '" + key + "')";
    if (const std::string near = NearestName(section, Sections()); !near.empty()) {
      text += "; line " + std::to_string(SectionLine(near)) + " has [" + near + "]: a typo of it?";
    }
    throw ConfigError(text);
  }
  const auto k = s->second.find(key);
  if (k == s->second.end()) {
    // The section's header line, and a key of the section nobody read that looks like a typo of
    // this one (or this key in another section).
    std::string text = origin_ + ":" + std::to_string(SectionLine(section)) + ": missing key '" + key +
                       "' in section [" + section + "] (the section begins on this line)";
    std::vector<std::string> unread;
    for (const auto& [name, entry] : s->second) {
      if (!used_.count({section, name})) unread.push_back(name);
    }
    if (const std::string near = NearestName(key, unread); !near.empty()) {
      text += "; line " + std::to_string(KeyLine(section, near)) + " has '" + near + "': a typo of it?";
    } else {
      for (const auto& [other, entries] : sections_) {
        if (other != section && entries.count(key)) {
          text +=
              "; line " + std::to_string(entries.at(key).line) + " has it in [" + other + "]: in the wrong section?";
          break;
        }
      }
    }
    throw ConfigError(text);
  }
  used_.insert({section, key});
  return k->second;
}

void IniFile::Fail(const Entry& e, const std::string& section, const std::string& key, const std::string& why) const {
  throw ConfigError(origin_ + ":" + std::to_string(e.line) + ": [" + section + "] " + key + " = '" + e.value + "': " + why);
}

void IniFile::FailKey(const std::string& section, const std::string& key, const std::string& why) const {
  const auto s = sections_.find(section);
  if (s == sections_.end()) throw ConfigError(origin_ + ": [" + section + "] " + key + ": " + why);
  if (const auto k = s->second.find(key); k != s->second.end()) Fail(k->second, section, key, why);
  throw ConfigError(origin_ + ":" + std::to_string(SectionLine(section)) + ": [" + section + "] " + key + ": " + why);
}

ConfigError IniFile::ValidationError(const std::string& what) const {
  // The keys read from this file that the message names as words (an option in radians names
  // its key in degrees: InDegrees), in file order; failing that, those a word ends with or that
  // end with a word, at a '_' (the option `gain` of the key `illumination_gain`,
  // `robot_radius_m` of `radius_m`). "[section]" or "section.key" in the message narrows a key
  // name read in several sections.
  using Named = std::pair<int, std::pair<std::string, std::string>>;  // (line, (section, key))
  const std::set<std::string> words = Words(what);
  const auto ends_with = [](const std::string& text, const std::string& tail) {
    // A unit ("m", "px", "deg") is no name: the tail has a '_' or four characters at least.
    return (tail.size() >= 4 || tail.find('_') != std::string::npos) && text.size() > tail.size() &&
           text.compare(text.size() - tail.size(), tail.size(), tail) == 0 &&
           text[text.size() - tail.size() - 1] == '_';
  };
  // A word names a key that it ends with, or that ends with it, at a '_'; of the keys one word
  // names so, those sharing the longest tail with it (`loop_search_sigmas` names
  // `graph_loop_search_sigmas`, not `search_sigmas`).
  const auto tail = [&](const std::string& w, const std::string& key) -> size_t {
    return ends_with(w, key) || ends_with(key, w) ? std::min(w.size(), key.size()) : 0;
  };
  std::map<std::string, size_t> longest_tail;  // by word, over the keys that may be named
  const auto suffix_match = [&](const std::string& key) {
    for (const auto& w : words) {
      const size_t t = tail(w, key);
      if (t > 0 && t == longest_tail[w]) return true;
    }
    return false;
  };
  // A name that is a plain word ("map", "scan", "home") may be a word of the message's prose: a
  // channel key counts only when the message names [channels], and a plain key only when the
  // message names no key with a '_' in it.
  const auto named_section = [&](const std::string& section, const std::string& key) {
    return what.find("[" + section + "]") != std::string::npos || what.find(section + "." + key) != std::string::npos;
  };
  std::vector<Named> named, narrowed;
  for (const auto& [section, key] : used_) {
    if (section == "channels" && !named_section(section, key)) continue;
    for (const auto& w : words) longest_tail[w] = std::max(longest_tail[w], tail(w, key));
  }
  for (const bool exact : {true, false}) {
    for (const auto& [section, key] : used_) {
      if (exact ? !words.count(key) : !suffix_match(key)) continue;
      if (section == "channels" && !named_section(section, key)) continue;
      named.push_back({KeyLine(section, key), {section, key}});
      if (named_section(section, key)) narrowed.push_back(named.back());
    }
    if (!named.empty()) break;
  }
  if (!narrowed.empty()) named = narrowed;
  const auto plain = [](const Named& n) { return n.second.second.find('_') == std::string::npos; };
  if (!std::all_of(named.begin(), named.end(), plain))
    named.erase(std::remove_if(named.begin(), named.end(), plain), named.end());
  if (named.empty()) return ConfigError(origin_ + ": " + what);
  std::sort(named.begin(), named.end());
  std::string text;
  for (size_t i = 0; i < named.size(); ++i) {
    const auto& [section, key] = named[i].second;
    const std::string line = std::to_string(named[i].first);
    const std::string value = " = '" + sections_.at(section).at(key).value + "'";
    if (i == 0) {
      text = origin_ + ":" + line + ": [" + section + "] " + key + value;
      continue;
    }
    const bool same_section = section == named[i - 1].second.first;
    text += (i == 1 ? " (" : ", ") + std::string("line ") + line + ": " + (same_section ? "" : "[" + section + "] ") +
            key + value;
  }
  if (named.size() > 1) text += ")";
  return ConfigError(text + ": " + what);
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
  // What the program read: its keys per section.
  std::map<std::string, std::vector<std::string>> known;
  for (const auto& [section, key] : used_) known[section].push_back(key);
  std::vector<std::string> known_sections;
  for (const auto& [section, keys] : known) known_sections.push_back(section);
  std::vector<std::pair<int, std::string>> unknown;  // (line, text), in file order
  for (const auto& [section, entries] : sections_) {
    for (const auto& [key, e] : entries) {
      if (used_.count({section, key})) continue;
      std::string text = origin_ + ":" + std::to_string(e.line) + ": [" + section + "] " + key;
      std::string elsewhere;  // a section where the program reads this key
      for (const auto& [other, keys] : known) {
        if (other != section && std::find(keys.begin(), keys.end(), key) != keys.end()) elsewhere = other;
      }
      const auto read = known.find(section);
      if (read != known.end()) {
        if (const std::string near = NearestName(key, read->second); !near.empty()) {
          text += " (did you mean '" + near + "'?)";
        } else if (!elsewhere.empty()) {
          text += " (a key of [" + elsewhere + "], not of [" + section + "])";
        }
      } else if (!elsewhere.empty()) {
        text += " (a key of [" + elsewhere + "]; this program reads no [" + section + "])";
      } else if (const std::string near = NearestName(section, known_sections); !near.empty()) {
        text += " (this program reads no [" + section + "]; did you mean [" + near + "]?)";
      }
      unknown.emplace_back(e.line, text);
    }
  }
  std::sort(unknown.begin(), unknown.end());
  std::string list;
  for (const auto& item : unknown) list += "\n  " + item.second;
  if (!list.empty()) throw ConfigError("unknown config keys (typo, or not an option of this program):" + list);
}

}  // namespace snapnav::glue
