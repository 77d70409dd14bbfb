#include "snapnav/glue/flags.hpp"

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <sstream>

#include "snapnav/glue/suggest.hpp"

namespace snapnav::glue {
namespace {

double ParseDouble(const std::string& name, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || errno == ERANGE) {
    throw FlagError("--" + name + " expects a number, got '" + text + "'");
  }
  return v;
}

int ParseInt(const std::string& name, const std::string& text) {
  char* end = nullptr;
  errno = 0;
  const long v = std::strtol(text.c_str(), &end, 10);
  if (text.empty() || *end != '\0' || errno == ERANGE || v < INT32_MIN || v > INT32_MAX) {
    throw FlagError("--" + name + " expects an integer, got '" + text + "'");
  }
  return static_cast<int>(v);
}

bool Mentions(const std::string& help, const std::string& word) {
  std::string lower = help;
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return lower.find(word) != std::string::npos;
}

// The default --help shows: `given` when given; none when the help says what it is ("default: ...")
// or that the flag overrides a config key (the config's value is the default), or for a NaN (a
// sentinel for "not given"); else `value`.
std::string DefaultText(const std::string& help, const std::string& value, const char* given) {
  if (given) return given;
  if (Mentions(help, "default") || Mentions(help, "override") || value == "nan" || value == "-nan") return "";
  return value;
}

}  // namespace

Flags::Flags(std::string program, std::string summary) : program_(std::move(program)), summary_(std::move(summary)) {
  // "log-report LOG": the binary's name, then its positional arguments.
  if (const auto space = program_.find(' '); space != std::string::npos) {
    positional_synopsis_ = program_.substr(space + 1);
    program_.resize(space);
  }
}

void Flags::Add(Flag flag) {
  for (const auto& f : flags_) {
    if (f.name == flag.name) throw std::logic_error("flag --" + flag.name + " defined twice");
  }
  flags_.push_back(std::move(flag));
}

void Flags::AddString(const std::string& name, std::string* value, const std::string& help, const char* default_text) {
  Add({name, help, DefaultText(help, *value, default_text), false, [value](const std::string& v) { *value = v; }});
}

void Flags::AddInt(const std::string& name, int* value, const std::string& help, const char* default_text) {
  Add({name, help, DefaultText(help, std::to_string(*value), default_text), false,
       [value, name](const std::string& v) { *value = ParseInt(name, v); }});
}

void Flags::AddDouble(const std::string& name, double* value, const std::string& help, const char* default_text) {
  std::ostringstream def;
  def << *value;
  Add({name, help, DefaultText(help, def.str(), default_text), false,
       [value, name](const std::string& v) { *value = ParseDouble(name, v); }});
}

void Flags::AddBool(const std::string& name, bool* value, const std::string& help) {
  Add({name, help, "", true, [value](const std::string&) { *value = true; }});
}

void Flags::AddStringList(const std::string& name, std::vector<std::string>* values, const std::string& help) {
  Add({name, Mentions(help, "repeatable") ? help : help + " (repeatable)", "", false,
       [values](const std::string& v) { values->push_back(v); }});
}

void Flags::AddCommon(CommonFlags* common) {
  AddString("config", &common->config, "INI file with this process's options");
  AddString("lcm-url", &common->lcm_url,
            "LCM provider URL (default: $LCM_DEFAULT_URL or host-local UDP multicast); "
            "file://LOG?speed=0 and memq:// work too");
  AddString("channel-prefix", &common->channel_prefix, "prefix prepended to every channel name");
}

void Flags::AllowPositional(const std::string& synopsis, const std::string& help) {
  positional_synopsis_ = synopsis;
  positional_help_ = help;
  positional_allowed_ = true;
}

bool Flags::Parse(int argc, char** argv) { return Parse(argc, argv, std::cout); }

bool Flags::Parse(int argc, const char* const* argv, std::ostream& out) {
  positional_.clear();
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      PrintUsage(out);
      return false;
    }
    if (arg.rfind("--", 0) != 0 || arg.size() == 2) {
      if (!positional_allowed_) throw FlagError("unexpected argument '" + arg + "' (see --help)");
      positional_.push_back(arg);
      continue;
    }
    std::string name = arg.substr(2);
    std::string value;
    bool has_value = false;
    if (const auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
      has_value = true;
    }
    const Flag* flag = nullptr;
    for (const auto& f : flags_) {
      if (f.name == name) flag = &f;
    }
    if (!flag) {
      std::vector<std::string> names;
      for (const auto& f : flags_) names.push_back(f.name);
      names.push_back("help");
      const std::string near = NearestName(name, names);
      throw FlagError("unknown flag --" + name + (near.empty() ? "" : " (did you mean --" + near + "?)") +
                      " (see --help)");
    }
    if (flag->is_bool) {
      if (has_value) throw FlagError("--" + name + " takes no value");
    } else if (!has_value) {
      if (i + 1 >= argc) throw FlagError("--" + name + " needs a value");
      value = argv[++i];
    }
    flag->set(value);
  }
  return true;
}

void Flags::PrintUsage(std::ostream& out) const {
  out << "usage: " << program_ << " [flags]";
  if (!positional_synopsis_.empty()) out << " " << positional_synopsis_;
  out << "\n\n" << summary_ << "\n\nflags:\n";
  for (const auto& f : flags_) {
    std::string left = "  --" + f.name + (f.is_bool ? "" : " VALUE");
    out << std::left << std::setw(28) << left << " " << f.help;
    if (!f.is_bool && !f.default_text.empty()) out << " (default: " << f.default_text << ")";
    out << "\n";
  }
  if (positional_allowed_)
    out << "  " << std::left << std::setw(27) << positional_synopsis_ << " " << positional_help_ << "\n";
  out << "  " << std::left << std::setw(27) << "--help" << " print this help\n";
}

std::vector<std::string> SplitList(const std::string& text, char sep) {
  std::vector<std::string> parts;
  std::string cur;
  std::istringstream in(text);
  while (std::getline(in, cur, sep)) {
    const auto b = cur.find_first_not_of(" \t");
    const auto e = cur.find_last_not_of(" \t");
    parts.push_back(b == std::string::npos ? "" : cur.substr(b, e - b + 1));
  }
  return parts;
}

}  // namespace snapnav::glue
