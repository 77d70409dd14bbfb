#include "snapnav/glue/flags.hpp"

#include <cerrno>
#include <cstdlib>
#include <iomanip>
#include <iostream>
#include <sstream>

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

}  // namespace

Flags::Flags(std::string program, std::string summary) : program_(std::move(program)), summary_(std::move(summary)) {}

void Flags::Add(Flag flag) {
  for (const auto& f : flags_) {
    if (f.name == flag.name) throw std::logic_error("flag --" + flag.name + " defined twice");
  }
  flags_.push_back(std::move(flag));
}

void Flags::AddString(const std::string& name, std::string* value, const std::string& help) {
  Add({name, help, *value, false, [value](const std::string& v) { *value = v; }});
}

void Flags::AddInt(const std::string& name, int* value, const std::string& help) {
  Add({name, help, std::to_string(*value), false, [value, name](const std::string& v) { *value = ParseInt(name, v); }});
}

void Flags::AddDouble(const std::string& name, double* value, const std::string& help) {
  std::ostringstream def;
  def << *value;
  Add({name, help, def.str(), false, [value, name](const std::string& v) { *value = ParseDouble(name, v); }});
}

void Flags::AddBool(const std::string& name, bool* value, const std::string& help) {
  Add({name, help, "", true, [value](const std::string&) { *value = true; }});
}

void Flags::AddStringList(const std::string& name, std::vector<std::string>* values, const std::string& help) {
  Add({name, help + " (repeatable)", "", false, [values](const std::string& v) { values->push_back(v); }});
}

void Flags::AddCommon(CommonFlags* common) {
  AddString("config", &common->config, "INI file with this process's options");
  AddString("lcm-url", &common->lcm_url,
            "LCM provider URL (default: $LCM_DEFAULT_URL or host-local UDP multicast); "
            "file://LOG?speed=0 and memq:// work too");
  AddString("channel-prefix", &common->channel_prefix, "prefix prepended to every channel name");
}

void Flags::AllowPositional(const std::string& name, const std::string& help) {
  positional_name_ = name;
  positional_help_ = help;
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
      if (positional_name_.empty()) throw FlagError("unexpected argument '" + arg + "' (see --help)");
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
    if (!flag) throw FlagError("unknown flag --" + name + " (see --help)");
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
  if (!positional_name_.empty()) out << " " << positional_name_ << "...";
  out << "\n\n" << summary_ << "\n\nflags:\n";
  for (const auto& f : flags_) {
    std::string left = "  --" + f.name + (f.is_bool ? "" : " VALUE");
    out << std::left << std::setw(28) << left << " " << f.help;
    if (!f.is_bool && !f.default_text.empty()) out << " (default: " << f.default_text << ")";
    out << "\n";
  }
  if (!positional_name_.empty()) out << "  " << std::left << std::setw(27) << positional_name_ << " " << positional_help_ << "\n";
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
