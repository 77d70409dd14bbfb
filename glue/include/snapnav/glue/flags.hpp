#pragma once
// Command-line flags: `--name value` or `--name=value`, `--help` prints usage.
// Unknown flags, missing values and malformed numbers are errors.

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
  Flags(std::string program, std::string summary);

  void AddString(const std::string& name, std::string* value, const std::string& help);
  void AddInt(const std::string& name, int* value, const std::string& help);
  void AddDouble(const std::string& name, double* value, const std::string& help);
  void AddBool(const std::string& name, bool* value, const std::string& help);  // presence sets true
  // May be given several times; each value is appended.
  void AddStringList(const std::string& name, std::vector<std::string>* values, const std::string& help);
  void AddCommon(CommonFlags* common);
  // Positional arguments are accepted only if a name for them is given.
  void AllowPositional(const std::string& name, const std::string& help);

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
  std::string positional_name_;
  std::string positional_help_;
  std::vector<std::string> positional_;
};

// Splits "a,b,c" into its parts (empty input: no parts).
std::vector<std::string> SplitList(const std::string& text, char sep = ',');

}  // namespace snapnav::glue
