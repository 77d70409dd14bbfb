#include "deployment.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <iterator>
#include <fstream>
#include <regex>
#include <sstream>
#include <stdexcept>

#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/suggest.hpp"

namespace snapnav::launch {
namespace {

const char* const kProcessKeys[] = {"command",        "host",          "group",
                                    "required",       "if_missing",    "restart",
                                    "restart_limit",  "restart_delay_s", "restart_delay_max_s",
                                    "stop_signal",    "stop_grace_s",  "ready",
                                    "ready_timeout_s", "exit_stops_all", "log_file",
                                    "echo"};
const char* const kBuiltins[] = {"bin", "config", "root", "out", "lcm_url", "host"};

bool IsProcessKey(const std::string& key) {
  for (const char* k : kProcessKeys) {
    if (key == k) return true;
  }
  return false;
}

bool IsBuiltin(const std::string& name) {
  for (const char* b : kBuiltins) {
    if (name == b) return true;
  }
  return false;
}

bool ValidName(const std::string& name) {
  if (name.empty()) return false;
  for (const char c : name) {
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  }
  return true;
}

std::string Trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

// "WORD REST" -> (WORD, REST).
std::pair<std::string, std::string> FirstWord(const std::string& text) {
  const std::string t = Trim(text);
  const auto sp = t.find_first_of(" \t");
  if (sp == std::string::npos) return {t, ""};
  return {t.substr(0, sp), Trim(t.substr(sp))};
}

// Resolves ${NAME}: built-ins, then [variables] (substituted themselves, cycles refused).
class Variables {
 public:
  Variables(const glue::IniFile& ini, const LoadOptions& options, Deployment* deployment)
      : ini_(ini), options_(options), deployment_(deployment) {
    for (const auto& key : ini.Keys("variables")) {
      const std::string at = ini.origin() + ":" + std::to_string(ini.KeyLine("variables", key));
      if (IsBuiltin(key)) {
        throw ConfigError(at + ": [variables] " + key + ": '" + key +
                          "' is a built-in variable (set it with the launcher's --" + (key == "lcm_url" ? "lcm-url" : key) +
                          " flag)");
      }
      if (!ValidName(key)) throw ConfigError(at + ": [variables] '" + key + "': not a valid variable name");
      raw_[key] = {ini.GetString("variables", key), at};
    }
    for (const auto& [name, value] : options.overrides) {
      const auto it = raw_.find(name);
      if (it == raw_.end()) {
        std::string known;
        for (const auto& [k, _] : raw_) known += (known.empty() ? "" : ", ") + k;
        throw ConfigError(ini.origin() + ": variable '" + name + "' set on the " + options.overrides_origin +
                          " is not in [variables]" +
                          (known.empty() ? " (the file has none)" : " (the file has: " + known + ")"));
      }
      it->second = {value, options.overrides_origin + " " + name + "=" + value};
    }
    for (const auto& [name, _] : raw_) deployment_->variables[name] = Resolve(name);
  }

  std::optional<std::string> Lookup(const std::string& name) {
    if (const auto it = extra_.find(name); it != extra_.end()) return it->second;
    if (IsBuiltin(name)) {
      const auto it = options_.builtins.find(name);
      if (it == options_.builtins.end()) return std::nullopt;
      deployment_->used_builtins.insert(name);
      return it->second;
    }
    if (raw_.count(name)) return Resolve(name);
    return std::nullopt;
  }

  // Variables known until the next SetExtra (an include's ${VAR} and ${index}).
  void SetExtra(std::map<std::string, std::string> extra) { extra_ = std::move(extra); }

  // `text` with its variables substituted; errors name `at`.
  std::string Apply(const std::string& text, const std::string& at) {
    try {
      return Substitute(text, [this](const std::string& n) { return Lookup(n); });
    } catch (const std::invalid_argument& e) {
      throw ConfigError(at + ": " + e.what() + KnownList());
    }
  }

 private:
  std::string Resolve(const std::string& name) {
    if (const auto it = resolved_.find(name); it != resolved_.end()) return it->second;
    if (resolving_.count(name)) throw ConfigError(raw_.at(name).second + ": variable '" + name + "' refers to itself");
    resolving_.insert(name);
    const std::string value = Apply(raw_.at(name).first, raw_.at(name).second + ": [variables] " + name);
    resolving_.erase(name);
    return resolved_[name] = value;
  }

  std::string KnownList() const {
    std::string known;
    for (const char* b : kBuiltins) known += std::string(known.empty() ? "" : ", ") + b;
    for (const auto& [k, _] : raw_) known += ", " + k;
    for (const auto& [k, _] : extra_) known += ", " + k;
    return " (known: " + known + ")";
  }

  const glue::IniFile& ini_;
  const LoadOptions& options_;
  Deployment* deployment_;
  std::map<std::string, std::pair<std::string, std::string>> raw_;  // name -> (value, where)
  std::map<std::string, std::string> resolved_;
  std::set<std::string> resolving_;
  std::map<std::string, std::string> extra_;
};

// The keys of one [process NAME] section, falling back to [defaults].
class ProcessReader {
 public:
  ProcessReader(const glue::IniFile& ini, std::string section, std::string name, Variables* vars)
      : ini_(ini), section_(std::move(section)), name_(std::move(name)), vars_(vars) {}

  struct Value {
    std::string text;  // variables substituted
    std::string at;    // "FILE:LINE: [section] key = 'raw'"
  };

  Value Raw(const std::string& key) const {
    for (const std::string& s : {section_, std::string("defaults")}) {
      if (ini_.Has(s, key)) {
        const std::string raw = ini_.GetString(s, key);
        return {raw, ini_.origin() + ":" + std::to_string(ini_.KeyLine(s, key)) + ": [" + s + "] " + key + " = '" +
                         raw + "'"};
      }
    }
    throw ConfigError(ini_.origin() + ":" + std::to_string(ini_.SectionLine(section_)) + ": [" + section_ +
                      "]: missing key '" + key + "'" +
                      (key == "command" ? std::string() : " (set it here or in [defaults])"));
  }
  Value Get(const std::string& key) const {
    Value v = Raw(key);
    v.text = vars_->Apply(v.text, v.at);
    return v;
  }

  [[noreturn]] static void Fail(const Value& v, const std::string& why) { throw ConfigError(v.at + ": " + why); }

  double Double(const std::string& key, double min) const {
    const Value v = Get(key);
    char* end = nullptr;
    errno = 0;
    const double d = std::strtod(v.text.c_str(), &end);
    if (v.text.empty() || *end != '\0' || errno == ERANGE || !std::isfinite(d)) Fail(v, "expected a number");
    if (d < min) {
      std::ostringstream m;
      m << "must be at least " << min;
      Fail(v, m.str());
    }
    return d;
  }
  int Int(const std::string& key, int min) const {
    const Value v = Get(key);
    char* end = nullptr;
    errno = 0;
    const long i = std::strtol(v.text.c_str(), &end, 10);
    if (v.text.empty() || *end != '\0' || errno == ERANGE || i > 1'000'000) Fail(v, "expected an integer");
    if (i < min) Fail(v, "must be at least " + std::to_string(min));
    return static_cast<int>(i);
  }
  bool Bool(const std::string& key) const {
    const Value v = Get(key);
    if (v.text == "true" || v.text == "yes" || v.text == "on" || v.text == "1") return true;
    if (v.text == "false" || v.text == "no" || v.text == "off" || v.text == "0") return false;
    Fail(v, "expected true or false");
  }
  template <class E>
  E Choice(const std::string& key, std::initializer_list<std::pair<const char*, E>> choices) const {
    const Value v = Get(key);
    std::string names;
    for (const auto& [n, e] : choices) {
      if (v.text == n) return e;
      names += names.empty() ? n : std::string(" | ") + n;
    }
    Fail(v, "expected " + names);
  }

  const std::string& section() const { return section_; }

 private:
  const glue::IniFile& ini_;
  std::string section_;
  std::string name_;
  Variables* vars_;
};

void CheckRegex(const ProcessReader::Value& v, const std::string& pattern) {
  try {
    std::regex re(pattern);
  } catch (const std::regex_error& e) {
    ProcessReader::Fail(v, "not a valid regular expression: " + std::string(e.what()));
  }
}

ProcessSpec ReadProcess(const glue::IniFile& ini, const std::string& section, const std::string& name,
                        Variables* vars) {
  const ProcessReader r(ini, section, name, vars);
  ProcessSpec p;
  p.name = name;
  p.where = ini.origin() + ":" + std::to_string(ini.SectionLine(section));

  const auto command = r.Raw("command");
  std::vector<std::string> words;
  try {
    words = SplitCommand(command.text);
  } catch (const std::invalid_argument& e) {
    ProcessReader::Fail(command, e.what());
  }
  if (words.empty()) ProcessReader::Fail(command, "empty command");
  for (const auto& w : words) p.argv.push_back(vars->Apply(w, command.at));

  p.host = r.Get("host").text;
  if (p.host.empty() || p.host.find_first_of(" \t,") != std::string::npos) {
    ProcessReader::Fail(r.Get("host"), "expected one host name, * or localhost");
  }
  p.group = r.Get("group").text;
  if (!ValidName(p.group)) ProcessReader::Fail(r.Get("group"), "expected a group name (letters, digits, _ - .)");
  p.required = r.Bool("required");
  p.if_missing = r.Choice<IfMissing>("if_missing", {{"error", IfMissing::kError}, {"skip", IfMissing::kSkip}});
  p.restart = r.Choice<RestartPolicy>(
      "restart", {{"never", RestartPolicy::kNever}, {"on-failure", RestartPolicy::kOnFailure}, {"always", RestartPolicy::kAlways}});
  p.restart_limit = r.Int("restart_limit", 0);
  p.restart_delay_s = r.Double("restart_delay_s", 0);
  p.restart_delay_max_s = r.Double("restart_delay_max_s", 0);
  if (p.restart_delay_max_s < p.restart_delay_s) {
    ProcessReader::Fail(r.Get("restart_delay_max_s"), "must be at least restart_delay_s (" + r.Get("restart_delay_s").text + ")");
  }
  {
    const auto v = r.Get("stop_signal");
    try {
      p.stop_signal = ParseSignal(v.text);
    } catch (const std::invalid_argument& e) {
      ProcessReader::Fail(v, e.what());
    }
  }
  p.stop_grace_s = r.Double("stop_grace_s", 0);
  if (p.stop_grace_s <= 0) ProcessReader::Fail(r.Get("stop_grace_s"), "must be > 0");

  {
    const auto v = r.Get("ready");
    const auto [kind, arg] = FirstWord(v.text);
    if (kind == "none" && arg.empty()) {
      p.ready = ReadyKind::kNone;
    } else if (kind == "exited" && arg.empty()) {
      p.ready = ReadyKind::kExited;
    } else if (kind == "delay") {
      char* end = nullptr;
      p.ready_delay_s = std::strtod(arg.c_str(), &end);
      if (arg.empty() || *end != '\0' || !(p.ready_delay_s >= 0)) ProcessReader::Fail(v, "expected 'delay SECONDS'");
      p.ready = ReadyKind::kDelay;
    } else if (kind == "line" && !arg.empty()) {
      CheckRegex(v, arg);
      p.ready = ReadyKind::kLine;
      p.ready_pattern = arg;
    } else if (kind == "file" && !arg.empty()) {
      p.ready = ReadyKind::kFile;
      p.ready_pattern = arg;
    } else {
      ProcessReader::Fail(v, "expected none | delay SECONDS | line REGEX | file PATH | exited");
    }
  }
  p.ready_timeout_s = r.Double("ready_timeout_s", 0);
  if (p.ready_timeout_s <= 0) ProcessReader::Fail(r.Get("ready_timeout_s"), "must be > 0");
  p.exit_stops_all = r.Bool("exit_stops_all");
  {
    const auto v = r.Get("log_file");
    if (v.text.empty()) ProcessReader::Fail(v, "expected a path or none");
    p.log_file = v.text == "none" ? "" : v.text;
  }
  {
    const auto v = r.Get("echo");
    const auto [kind, arg] = FirstWord(v.text);
    if (kind == "all" && arg.empty()) {
      p.echo = EchoMode::kAll;
    } else if (kind == "none" && arg.empty()) {
      p.echo = EchoMode::kNone;
    } else if (kind == "match" && !arg.empty()) {
      CheckRegex(v, arg);
      p.echo = EchoMode::kMatch;
      p.echo_pattern = arg;
    } else {
      ProcessReader::Fail(v, "expected all | none | match REGEX");
    }
  }
  return p;
}

std::string KnownProcessKeys() {
  std::string keys;
  for (const char* k : kProcessKeys) keys += std::string(keys.empty() ? "" : ", ") + k;
  return keys;
}

// "unknown key (did you mean 'X'?) (process keys: ...)".
std::string UnknownProcessKey(const std::string& key) {
  return "unknown key" +
         glue::DidYouMean(key, std::vector<std::string>(std::begin(kProcessKeys), std::end(kProcessKeys))) +
         " (process keys: " + KnownProcessKeys() + ")";
}

// The processes of one [include NAME] section: the other file, once or once per for_each value,
// with the section's other keys as its variables; appended to `d` under their qualified names.
void ReadInclude(const glue::IniFile& ini, const std::string& section, const std::string& name, Variables* vars,
                 const LoadOptions& options, Deployment* d) {
  const std::string origin = ini.origin();
  const auto at = [&](const std::string& key) {
    return origin + ":" + std::to_string(key.empty() ? ini.SectionLine(section) : ini.KeyLine(section, key)) + ": [" +
           section + "]" + (key.empty() ? "" : " " + key);
  };
  if (!ini.Has(section, "file")) throw ConfigError(at("") + ": missing key 'file' (the deployment file to include)");
  if (options.include_depth >= kMaxIncludeDepth) {
    throw ConfigError(at("") + ": includes nested more than " + std::to_string(kMaxIncludeDepth) +
                      " deep (does a file include itself?)");
  }
  // for_each = VAR in V1,V2,...: one copy per value.
  std::string loop_var;
  std::vector<std::string> values{""};
  if (ini.Has(section, "for_each")) {
    const std::string text = vars->Apply(ini.GetString(section, "for_each"), at("for_each"));
    static const std::regex form(R"(^\s*([A-Za-z0-9_.-]+)\s+in\s+(.*\S)\s*$)");
    std::smatch m;
    if (!std::regex_match(text, m, form)) {
      throw ConfigError(at("for_each") + " = '" + text + "': expected 'VARIABLE in VALUE1,VALUE2,...'");
    }
    loop_var = m[1];
    if (IsBuiltin(loop_var) || loop_var == "index") {
      throw ConfigError(at("for_each") + ": '" + loop_var + "' is a built-in variable; pick another name");
    }
    values = glue::SplitList(m[2]);
    if (values.empty()) throw ConfigError(at("for_each") + ": no values");
  }
  // processes = P1,P2,...: only these of the other file's processes (in that file's order).
  std::set<std::string> only;
  if (ini.Has(section, "processes")) {
    for (const auto& p : glue::SplitList(vars->Apply(ini.GetString(section, "processes"), at("processes")))) only.insert(p);
    if (only.empty()) throw ConfigError(at("processes") + ": no process names");
  }
  for (size_t k = 0; k < values.size(); ++k) {
    const std::string copy = loop_var.empty() ? name : name + std::to_string(k + 1);
    std::map<std::string, std::string> extra;
    if (!loop_var.empty()) extra = {{loop_var, values[k]}, {"index", std::to_string(k + 1)}};
    vars->SetExtra(extra);
    LoadOptions sub;
    sub.builtins = options.builtins;
    sub.include_depth = options.include_depth + 1;
    sub.overrides_origin = at("");
    std::filesystem::path file = vars->Apply(ini.GetString(section, "file"), at("file"));
    if (file.is_relative()) file = std::filesystem::path(origin).parent_path() / file;
    if (!loop_var.empty()) sub.overrides[loop_var] = values[k];  // the other file's variable of that name
    for (const auto& key : ini.Keys(section)) {
      if (key == "file" || key == "for_each" || key == "processes") continue;
      sub.overrides[key] = vars->Apply(ini.GetString(section, key), at(key));
    }
    vars->SetExtra({});
    Deployment included;
    try {
      included = LoadDeployment(file.string(), sub);
    } catch (const ConfigError& e) {
      throw ConfigError(std::string(e.what()) + "\n  (included by " + at("") + (loop_var.empty() ? "" : ", " + loop_var + " = " + values[k]) + ")");
    }
    for (const auto& name_only : only) {
      if (std::none_of(included.processes.begin(), included.processes.end(),
                       [&](const ProcessSpec& p) { return p.name == name_only; })) {
        std::string known;
        for (const auto& p : included.processes) known += (known.empty() ? "" : ", ") + p.name;
        throw ConfigError(at("processes") + ": " + file.string() + " has no process '" + name_only + "' (it has: " + known + ")");
      }
    }
    for (auto& p : included.processes) {
      if (!only.empty() && !only.count(p.name)) continue;
      p.name = copy + "." + p.name;
      d->processes.push_back(std::move(p));
    }
    for (const auto& [v, value] : included.variables) d->variables[copy + "." + v] = value;
    d->used_builtins.insert(included.used_builtins.begin(), included.used_builtins.end());
  }
}

}  // namespace

const char* RestartPolicyName(RestartPolicy p) {
  switch (p) {
    case RestartPolicy::kNever: return "never";
    case RestartPolicy::kOnFailure: return "on-failure";
    case RestartPolicy::kAlways: return "always";
  }
  return "?";
}

const char* ReadyKindName(ReadyKind k) {
  switch (k) {
    case ReadyKind::kNone: return "none";
    case ReadyKind::kDelay: return "delay";
    case ReadyKind::kLine: return "line";
    case ReadyKind::kFile: return "file";
    case ReadyKind::kExited: return "exited";
  }
  return "?";
}

std::string ProcessSpec::CommandLine() const {
  std::string out;
  for (const auto& a : argv) {
    if (!out.empty()) out += ' ';
    if (!a.empty() && a.find_first_of(" \t'\"\\$&|;<>()*?") == std::string::npos) {
      out += a;
    } else {
      out += '\'';
      for (const char c : a) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
      out += '\'';
    }
  }
  return out;
}

std::vector<std::string> SplitCommand(const std::string& text) {
  std::vector<std::string> words;
  std::string cur;
  bool in_word = false;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (c == ' ' || c == '\t') {
      if (in_word) words.push_back(cur);
      cur.clear();
      in_word = false;
    } else if (c == '\'') {
      const auto close = text.find('\'', i + 1);
      if (close == std::string::npos) throw std::invalid_argument("unbalanced ' in the command");
      cur += text.substr(i + 1, close - i - 1);
      i = close;
      in_word = true;
    } else if (c == '"') {
      in_word = true;
      size_t j = i + 1;
      for (; j < text.size() && text[j] != '"'; ++j) {
        if (text[j] == '\\' && j + 1 < text.size() && (text[j + 1] == '"' || text[j + 1] == '\\')) ++j;
        cur += text[j];
      }
      if (j >= text.size()) throw std::invalid_argument("unbalanced \" in the command");
      i = j;
    } else if (c == '\\') {
      if (i + 1 >= text.size()) throw std::invalid_argument("\\ at the end of the command");
      cur += text[++i];
      in_word = true;
    } else {
      cur += c;
      in_word = true;
    }
  }
  if (in_word) words.push_back(cur);
  return words;
}

std::string Substitute(const std::string& text,
                       const std::function<std::optional<std::string>(const std::string&)>& lookup) {
  std::string out;
  for (size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '$' || i + 1 >= text.size()) {
      out += text[i];
    } else if (text[i + 1] == '$') {
      out += '$';
      ++i;
    } else if (text[i + 1] == '{') {
      const auto close = text.find('}', i + 2);
      if (close == std::string::npos) throw std::invalid_argument("unterminated ${ in '" + text + "'");
      const std::string name = text.substr(i + 2, close - i - 2);
      const auto value = lookup(name);
      if (!value) throw std::invalid_argument("unknown variable ${" + name + "}");
      out += *value;
      i = close;
    } else {
      out += '$';
    }
  }
  return out;
}

bool HostMatches(const std::string& process_host, const std::string& this_host) {
  return process_host == "*" || process_host == "localhost" || process_host == this_host;
}

namespace {
const std::pair<const char*, int> kSignals[] = {{"HUP", SIGHUP},   {"INT", SIGINT},   {"QUIT", SIGQUIT},
                                                {"KILL", SIGKILL}, {"USR1", SIGUSR1}, {"USR2", SIGUSR2},
                                                {"TERM", SIGTERM}, {"ABRT", SIGABRT}, {"SEGV", SIGSEGV},
                                                {"PIPE", SIGPIPE}, {"ALRM", SIGALRM}, {"BUS", SIGBUS},
                                                {"FPE", SIGFPE},   {"ILL", SIGILL},   {"TRAP", SIGTRAP}};
}

int ParseSignal(const std::string& name) {
  const std::string n = name.rfind("SIG", 0) == 0 ? name.substr(3) : name;
  for (const auto& [s, v] : kSignals) {
    if (n == s) return v;
  }
  throw std::invalid_argument("unknown signal '" + name + "' (INT, TERM, HUP, QUIT, USR1, USR2 or KILL)");
}

std::string SignalName(int signal) {
  for (const auto& [s, v] : kSignals) {
    if (v == signal) return std::string("SIG") + s;
  }
  return "signal " + std::to_string(signal);
}

std::optional<std::string> FindProgram(const std::string& program) {
  if (program.empty()) return std::nullopt;
  if (program.find('/') != std::string::npos) {
    if (::access(program.c_str(), X_OK) == 0) return program;
    return std::nullopt;
  }
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "/usr/local/bin:/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    const std::string candidate = (dir.empty() ? "." : dir) + "/" + program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return std::nullopt;
}

Deployment ParseDeployment(const std::string& text, const std::string& origin, const LoadOptions& options) {
  const glue::IniFile ini = glue::IniFile::Parse(text, origin);
  Deployment d;
  d.path = origin;
  for (const auto& section : ini.SectionsInFileOrder()) {
    if (section == "deployment" || section == "variables" || section == "defaults" || section.rfind("process ", 0) == 0 ||
        section.rfind("include ", 0) == 0) {
      continue;
    }
    throw ConfigError(origin + ":" + std::to_string(ini.SectionLine(section)) + ": unknown section [" + section +
                      "] (expected [deployment], [variables], [defaults], [process NAME] or [include NAME])");
  }
  if (!ini.Has("deployment", "name")) {
    throw ConfigError(origin + (ini.SectionLine("deployment") ? ":" + std::to_string(ini.SectionLine("deployment")) : "") +
                      ": missing key 'name' in section [deployment]");
  }
  d.name = ini.GetString("deployment", "name");
  if (!ValidName(d.name)) {
    throw ConfigError(origin + ":" + std::to_string(ini.KeyLine("deployment", "name")) + ": [deployment] name = '" +
                      d.name + "': expected letters, digits, _ - .");
  }
  if (!ini.Has("deployment", "description")) {
    throw ConfigError(origin + ":" + std::to_string(ini.SectionLine("deployment")) +
                      ": missing key 'description' in section [deployment]");
  }
  d.description = ini.GetString("deployment", "description");
  for (const auto& key : ini.Keys("defaults")) {
    const std::string at = origin + ":" + std::to_string(ini.KeyLine("defaults", key));
    if (key == "command") throw ConfigError(at + ": [defaults] command: every process sets its own command");
    if (!IsProcessKey(key)) throw ConfigError(at + ": [defaults] " + key + ": " + UnknownProcessKey(key));
    ini.GetString("defaults", key);  // used; read again per process
  }
  Variables vars(ini, options, &d);
  std::set<std::string> names;
  for (const auto& section : ini.SectionsInFileOrder()) {
    const bool include = section.rfind("include ", 0) == 0;
    if (section.rfind("process ", 0) != 0 && !include) continue;
    const std::string name = Trim(section.substr(8));
    const std::string at = origin + ":" + std::to_string(ini.SectionLine(section));
    if (!ValidName(name)) {
      throw ConfigError(at + ": [" + section + "]: expected a" + (include ? "n include" : " process") +
                        " name (letters, digits, _ - .)");
    }
    const size_t before = d.processes.size();
    if (include) {
      ReadInclude(ini, section, name, &vars, options, &d);
    } else {
      for (const auto& key : ini.Keys(section)) {
        if (!IsProcessKey(key)) {
          throw ConfigError(origin + ":" + std::to_string(ini.KeyLine(section, key)) + ": [" + section + "] " + key +
                            ": " + UnknownProcessKey(key));
        }
      }
      d.processes.push_back(ReadProcess(ini, section, name, &vars));
    }
    for (size_t i = before; i < d.processes.size(); ++i) {
      if (!names.insert(d.processes[i].name).second) throw ConfigError(at + ": process '" + d.processes[i].name + "' defined twice");
    }
  }
  if (d.processes.empty()) throw ConfigError(origin + ": no [process NAME] section");
  ini.CheckAllUsed();
  return d;
}

Deployment LoadDeployment(const std::string& path, const LoadOptions& options) {
  std::ifstream in(path);
  if (!in) throw ConfigError("cannot open deployment file '" + path + "'");
  std::stringstream ss;
  ss << in.rdbuf();
  return ParseDeployment(ss.str(), path, options);
}

}  // namespace snapnav::launch
