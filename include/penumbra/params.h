// Technique parameters: a schema per technique (ParamSpec, listed by the registry), the values a
// user gave (ParamSet, each remembering where it came from), and the resolved values a technique is
// built with (Params). Validation happens in one place, resolveParams(): unknown names, wrong
// types and out-of-range values are rejected with the source named — never clamped, never ignored.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace penumbra {

enum class ParamType { Int, Float, Bool, String };
std::string_view toString(ParamType type);

using ParamValue = std::variant<int64_t, double, bool, std::string>;
std::string formatParamValue(const ParamValue& value);

struct ParamSpec {
  std::string name;
  ParamType type = ParamType::Float;
  ParamValue defaultValue;           //!< ignored when autoDefault is set
  std::optional<double> min;         //!< inclusive lower bound (Int, Float)
  std::optional<double> max;         //!< inclusive upper bound (Int, Float)
  std::vector<std::string> choices;  //!< allowed values of a String parameter (empty: any)
  std::string unit;                  //!< "texels", "world units", "samples", ...
  std::string help;
  bool autoDefault = false;  //!< default is "auto": derived from the physical light by the technique
};

// Values given by the user for one technique, before validation.
class ParamSet {
 public:
  struct Entry {
    ParamValue value;    //!< as given: a string from the command line, a typed value from JSON
    std::string source;  //!< "command line", "scene.json: techniques.pcss.kernel", ...
  };
  // Later values replace earlier ones (the command line overrides the scene file).
  void set(const std::string& name, ParamValue value, std::string source);
  // Parses "key=value" from the command line into a string entry.
  void setFromKeyValue(const std::string& keyValue, const std::string& source);
  const std::map<std::string, Entry>& entries() const { return entries_; }
  bool empty() const { return entries_.empty(); }
  bool has(const std::string& name) const { return entries_.count(name) != 0; }

 private:
  std::map<std::string, Entry> entries_;
};

// Resolved values: every parameter of the schema, typed, validated. A value of "auto" is kept as
// std::nullopt (isAuto) for the technique to derive.
class Params {
 public:
  Params() = default;
  int64_t getInt(const std::string& name) const;
  double getFloat(const std::string& name) const;  //!< also reads an Int parameter
  bool getBool(const std::string& name) const;
  const std::string& getString(const std::string& name) const;
  bool isAuto(const std::string& name) const;
  // The Float value, or `fallback` when the parameter is "auto".
  double getFloatOr(const std::string& name, double fallback) const;

  void set(const std::string& name, std::optional<ParamValue> value) { values_[name] = std::move(value); }
  const std::map<std::string, std::optional<ParamValue>>& values() const { return values_; }

 private:
  const ParamValue& find(const std::string& name) const;
  std::map<std::string, std::optional<ParamValue>> values_;
};

// Validates `given` against `schema` for technique `technique` and fills in defaults. Throws Error
// naming the source, the parameter and what was expected (and the known names for a typo).
Params resolveParams(const std::string& technique, const std::vector<ParamSpec>& schema, const ParamSet& given);

}  // namespace penumbra
