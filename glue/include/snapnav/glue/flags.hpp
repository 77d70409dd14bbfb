#pragma once
// Command-line flags: `--name value` or `--name=value`, `--help` prints usage.
// Unknown flags (with the nearest known one), missing values and malformed numbers are errors.
//
// --help: "usage: PROGRAM [flags] POSITIONAL", the summary, then one line per flag with its
// default: the variable's value when the flag was added, unless the help text already says what
// the default is (it contains "default"), or that the flag overrides a config key ("override":
// the config's value is the default), or the value is NaN (a sentinel), or `default_text` is
// given (printed instead; "": none, for a sentinel such as -1 meaning "the config's"). A list
// flag's help ends in "(repeatable)" once.

#include <functional>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <vector>

namespace snapnav::glue {

class FlagError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The flags every process takes.
struct CommonFlags {
  std::string config;          // INI file of the process
  std::string lcm_url;         // empty: DefaultLcmUrl()
  std::string channel_prefix;  // prepended to every channel name
};

class Flags {
 public:
  // `program` is the binary's name; words after it are taken as the positional arguments' synopsis
  // when AllowPositional does not give one.
  Flags(std::string program, std::string summary);

  void AddString(const std::string& name, std::string* value, const std::string& help,
                 const char* default_text = nullptr);
  void AddInt(const std::string& name, int* value, const std::string& help, const char* default_text = nullptr);
  void AddDouble(const std::string& name, double* value, const std::string& help, const char* default_text = nullptr);
  void AddBool(const std::string& name, bool* value, const std::string& help);  // presence sets true
  // May be given several times; each value is appended.
  void AddStringList(const std::string& name, std::vector<std::string>* values, const std::string& help);
  void AddCommon(CommonFlags* common);
  // Positional arguments are accepted only if they are named: `synopsis` as the usage line shows
  // them ("LOG", "DEPLOYMENT [NAME=VALUE...]"), `help` what they are.
  void AllowPositional(const std::string& synopsis, const std::string& help);

  // Returns false if --help was given (usage was printed to `out`).
  // Throws FlagError on bad input.
  bool Parse(int argc, const char* const* argv, std::ostream& out);
  bool Parse(int argc, char** argv);  // prints help to stdout

  const std::vector<std::string>& positional() const { return positional_; }
  void PrintUsage(std::ostream& out) const;

 private:
  struct Flag {
    std::string name;
    std::string help;
    std::string default_text;
    bool is_bool = false;
    std::function<void(const std::string&)> set;
  };
  void Add(Flag flag);

  std::string program_;
  std::string summary_;
  std::vector<Flag> flags_;
  std::string positional_synopsis_;  // from AllowPositional, else the words after the program's name
  std::string positional_help_;
  bool positional_allowed_ = false;
  std::vector<std::string> positional_;
};

// Splits "a,b,c" into its parts (empty input: no parts).
std::vector<std::string> SplitList(const std::string& text, char sep = ',');

}  // namespace snapnav::glue
