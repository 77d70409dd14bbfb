#pragma once
// A component's options declared once: each key with its unit and where it lives in the options
// struct; the one declaration reads the keys from an INI section, prints them back in the same
// form (the effective config every process prints at start), and describes them (key, unit,
// kind, the struct's default). The check is the struct's own Validate() (libnav keeps it beside
// the algorithm), run by Read through IniFile::Check so its complaint names file, line, section
// and key; ReadKeys reads without it, for a caller that checks several sections together.
//
//   const OptionTable<nav::Foo>& FooTable() {
//     static const auto table = OptionTable<nav::Foo>()
//         .Number("max_range_m", "m", &nav::Foo::max_range_m)
//         .Degrees("step_deg", &nav::Foo::step_rad)
//         .Number("sigma_m", "m", [](auto& o) -> auto& { return o.noise.sigma_m; });
//     return table;
//   }
//
// `access` is a pointer to a data member or a generic lambda returning a reference to the field
// (for nested structs); it is called on a const T when printing.

#include <cstdint>
#include <functional>
#include <initializer_list>
#include <ostream>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "snapnav/glue/flags.hpp"
#include "snapnav/glue/ini.hpp"

namespace snapnav::glue {

// One declared option.
struct OptionInfo {
  std::string key;
  std::string unit;           // "m", "deg", "s", ... ("" for counts, ratios and names)
  std::string kind;           // number | integer | flag | text | list | choice | custom
  std::string default_value;  // the options struct's default, printed as in a config file
  std::string choices;        // "a | b | c" for a choice
};

namespace options_detail {
template <class T, class = void>
struct HasValidate : std::false_type {};
template <class T>
struct HasValidate<T, std::void_t<decltype(std::declval<const T&>().Validate())>> : std::true_type {};
}  // namespace options_detail

template <class T>
class OptionTable {
 public:
  // File degrees <-> struct radians.
  static constexpr double kRadPerDeg = 3.14159265358979323846 / 180.0;

  // A number in the file's unit: a double, an int or a uint64_t field (by the type `access` yields;
  // a uint64_t, a seed, refuses a negative value).
  template <class F>
  OptionTable& Number(std::string key, std::string unit, F access) {
    using V = std::remove_cv_t<std::remove_reference_t<std::invoke_result_t<F, T&>>>;
    static_assert(std::is_same_v<V, double> || std::is_same_v<V, int> || std::is_same_v<V, uint64_t>,
                  "Number: the field must be a double, an int or a uint64_t (a seed)");
    const std::string k = key;
    return Add({std::move(key), std::move(unit), std::is_same_v<V, double> ? "number" : "integer", "", ""},
               [k, access](const IniFile& ini, const std::string& s, T& o) {
                 if constexpr (std::is_same_v<V, int>) {
                   std::invoke(access, o) = ini.GetInt(s, k);
                 } else if constexpr (std::is_same_v<V, uint64_t>) {
                   const int v = ini.GetInt(s, k);
                   if (v < 0) ini.FailKey(s, k, "must be >= 0");
                   std::invoke(access, o) = static_cast<uint64_t>(v);
                 } else {
                   std::invoke(access, o) = ini.GetDouble(s, k);
                 }
               },
               [access](std::ostream& out, const T& o) { out << std::invoke(access, o); });
  }
  // An angle: degrees in the file, radians in the struct (a double field). A rate or a density
  // of angles (deg/s, deg/m) is declared the same way with its unit.
  template <class F>
  OptionTable& Degrees(std::string key, F access, std::string unit = "deg") {
    const std::string k = key;
    return Add({std::move(key), std::move(unit), "number", "", ""},
               [k, access](const IniFile& ini, const std::string& s, T& o) {
                 std::invoke(access, o) = ini.GetDouble(s, k) * kRadPerDeg;
               },
               [access](std::ostream& out, const T& o) { out << std::invoke(access, o) / kRadPerDeg; });
  }
  // true | false.
  template <class F>
  OptionTable& Flag(std::string key, F access) {
    const std::string k = key;
    return Add({std::move(key), "", "flag", "", ""},
               [k, access](const IniFile& ini, const std::string& s, T& o) { std::invoke(access, o) = ini.GetBool(s, k); },
               [access](std::ostream& out, const T& o) { out << (std::invoke(access, o) ? "true" : "false"); });
  }
  // A string as written.
  template <class F>
  OptionTable& Text(std::string key, F access) {
    const std::string k = key;
    return Add({std::move(key), "", "text", "", ""},
               [k, access](const IniFile& ini, const std::string& s, T& o) { std::invoke(access, o) = ini.GetString(s, k); },
               [access](std::ostream& out, const T& o) { out << std::invoke(access, o); });
  }
  // A comma-separated list of names (a std::vector<std::string> field), printed as written.
  template <class F>
  OptionTable& List(std::string key, F access) {
    const std::string k = key;
    return Add({std::move(key), "", "list", "", ""},
               [k, access](const IniFile& ini, const std::string& s, T& o) { std::invoke(access, o) = SplitList(ini.GetString(s, k)); },
               [access](std::ostream& out, const T& o) {
                 const auto& names = std::invoke(access, o);
                 for (size_t i = 0; i < names.size(); ++i) out << (i ? "," : "") << names[i];
               });
  }
  // A key with its own reader and printer (a value with a special word, a unit conversion of its
  // own, a list of numbers): read(ini, section, key, o) and print(out, o).
  template <class R, class P>
  OptionTable& Custom(std::string key, std::string unit, R read, P print) {
    const std::string k = key;
    return Add({std::move(key), std::move(unit), "custom", "", ""},
               [k, read](const IniFile& ini, const std::string& s, T& o) { read(ini, s, k, o); },
               [print](std::ostream& out, const T& o) { print(out, o); });
  }
  // One of `choices` (name, value); anything else is an error listing them.
  template <class F, class E>
  OptionTable& Choice(std::string key, F access, std::vector<std::pair<std::string, E>> choices) {
    std::string names;
    for (const auto& c : choices) names += (names.empty() ? "" : " | ") + c.first;
    const std::string k = key;
    return Add({std::move(key), "", "choice", "", names},
               [k, access, choices, names](const IniFile& ini, const std::string& s, T& o) {
                 const std::string value = ini.GetString(s, k);
                 for (const auto& [name, e] : choices) {
                   if (value == name) {
                     std::invoke(access, o) = e;
                     return;
                   }
                 }
                 ini.FailKey(s, k, "expected " + names);
               },
               [access, choices](std::ostream& out, const T& o) {
                 for (const auto& [name, e] : choices) {
                   if (std::invoke(access, o) == e) {
                     out << name;
                     return;
                   }
                 }
                 out << "?";
               });
  }

  // The same with the names of libnav's own name function (e.g. nav::IcpMetricName).
  template <class F, class E, class NameFn>
  OptionTable& Choice(std::string key, F access, std::initializer_list<E> values, NameFn name) {
    std::vector<std::pair<std::string, E>> choices;
    for (E e : values) choices.emplace_back(name(e), e);
    return Choice(std::move(key), std::move(access), std::move(choices));
  }

  // Every declared key of `section` into *o (fields nobody declared keep their value), then, when
  // T has Validate(), the check: a complaint names file, line, section and key.
  void Read(const IniFile& ini, const std::string& section, T* o) const {
    ReadKeys(ini, section, o);
    if constexpr (options_detail::HasValidate<T>::value) ini.Check([o] { o->Validate(); });
  }
  // The keys only, for a caller that checks the struct itself (e.g. naming the key behind each of
  // the library's messages).
  void ReadKeys(const IniFile& ini, const std::string& section, T* o) const {
    for (const auto& e : entries_) e.read(ini, section, *o);
  }
  T Read(const IniFile& ini, const std::string& section) const {
    T o{};
    Read(ini, section, &o);
    return o;
  }
  // "key = value" per declared option, in declaration order (no section header).
  void Print(std::ostream& out, const T& o) const {
    for (const auto& e : entries_) {
      out << e.info.key << " = ";
      e.print(out, o);
      out << "\n";
    }
  }
  // The declarations, with `defaults`' values.
  std::vector<OptionInfo> Describe(const T& defaults = T{}) const {
    std::vector<OptionInfo> out;
    for (const auto& e : entries_) {
      OptionInfo i = e.info;
      std::ostringstream v;
      e.print(v, defaults);
      i.default_value = v.str();
      out.push_back(std::move(i));
    }
    return out;
  }
  size_t size() const { return entries_.size(); }

 private:
  using Reader = std::function<void(const IniFile&, const std::string&, T&)>;
  using Printer = std::function<void(std::ostream&, const T&)>;
  struct Entry {
    OptionInfo info;
    Reader read;
    Printer print;
  };
  OptionTable& Add(OptionInfo info, Reader read, Printer print) {
    entries_.push_back({std::move(info), std::move(read), std::move(print)});
    return *this;
  }
  std::vector<Entry> entries_;
};

}  // namespace snapnav::glue
