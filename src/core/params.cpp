#include "penumbra/params.h"

#include <algorithm>
#include <charconv>
#include <cmath>

#include <fmt/ranges.h>

#include "penumbra/error.h"

namespace penumbra {

std::string_view toString(ParamType type) {
  switch (type) {
    case ParamType::Int:
      return "int";
    case ParamType::Float:
      return "float";
    case ParamType::Bool:
      return "bool";
    case ParamType::String:
      return "string";
  }
  return "?";
}

std::string formatParamValue(const ParamValue& value) {
  return std::visit(
      [](const auto& v) -> std::string {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, bool>)
          return v ? "true" : "false";
        else if constexpr (std::is_same_v<T, std::string>)
          return v;
        else
          return fmt::format("{}", v);
      },
      value);
}

void ParamSet::set(const std::string& name, ParamValue value, std::string source) {
  entries_[name] = Entry{std::move(value), std::move(source)};
}

void ParamSet::setFromKeyValue(const std::string& keyValue, const std::string& source) {
  const size_t eq = keyValue.find('=');
  if (eq == std::string::npos || eq == 0)
    fail("{}: parameter '{}' must be written key=value (for example r_scale=0.5)", source, keyValue);
  set(keyValue.substr(0, eq), keyValue.substr(eq + 1), source);
}

namespace {

std::optional<double> parseNumber(const std::string& s) {
  double v = 0.0;
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, v);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return v;
}

std::string describeExpected(const ParamSpec& spec) {
  std::string s(toString(spec.type));
  if (spec.min && spec.max)
    s += fmt::format(" in [{}, {}]", *spec.min, *spec.max);
  else if (spec.min)
    s += fmt::format(" >= {}", *spec.min);
  else if (spec.max)
    s += fmt::format(" <= {}", *spec.max);
  if (!spec.choices.empty()) s += fmt::format(" (one of {})", fmt::join(spec.choices, ", "));
  if (spec.autoDefault) s += " or \"auto\"";
  return s;
}

// Converts a given value (string from the command line, typed from JSON) to the spec's type.
std::optional<ParamValue> convert(const ParamSpec& spec, const ParamValue& given) {
  const auto* str = std::get_if<std::string>(&given);
  switch (spec.type) {
    case ParamType::Int: {
      double d;
      if (str) {
        auto n = parseNumber(*str);
        if (!n) return std::nullopt;
        d = *n;
      } else if (auto* i = std::get_if<int64_t>(&given)) {
        return *i;
      } else if (auto* f = std::get_if<double>(&given)) {
        d = *f;
      } else {
        return std::nullopt;
      }
      if (!std::isfinite(d) || d != std::floor(d) || std::abs(d) > 9.0e15) return std::nullopt;
      return static_cast<int64_t>(d);
    }
    case ParamType::Float: {
      if (str) {
        auto n = parseNumber(*str);
        if (!n || !std::isfinite(*n)) return std::nullopt;
        return *n;
      }
      if (auto* i = std::get_if<int64_t>(&given)) return static_cast<double>(*i);
      if (auto* f = std::get_if<double>(&given))
        return std::isfinite(*f) ? std::optional<ParamValue>(*f) : std::nullopt;
      return std::nullopt;
    }
    case ParamType::Bool: {
      if (auto* b = std::get_if<bool>(&given)) return *b;
      if (str) {
        if (*str == "true" || *str == "1" || *str == "on" || *str == "yes") return true;
        if (*str == "false" || *str == "0" || *str == "off" || *str == "no") return false;
      }
      return std::nullopt;
    }
    case ParamType::String:
      if (str) return *str;
      return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

Params resolveParams(const std::string& technique, const std::vector<ParamSpec>& schema, const ParamSet& given) {
  for (const auto& [name, entry] : given.entries()) {
    bool known = false;
    for (const ParamSpec& spec : schema) known = known || spec.name == name;
    if (!known) {
      std::vector<std::string> names;
      for (const ParamSpec& spec : schema) names.push_back(spec.name);
      fail("{}: technique '{}' has no parameter '{}' (its parameters: {})", entry.source, technique, name,
           names.empty() ? std::string("none") : fmt::format("{}", fmt::join(names, ", ")));
    }
  }
  Params params;
  for (const ParamSpec& spec : schema) {
    auto it = given.entries().find(spec.name);
    if (it == given.entries().end()) {
      params.set(spec.name, spec.autoDefault ? std::nullopt : std::optional<ParamValue>(spec.defaultValue));
      continue;
    }
    const ParamSet::Entry& entry = it->second;
    const auto* str = std::get_if<std::string>(&entry.value);
    if (spec.autoDefault && str && *str == "auto") {
      params.set(spec.name, std::nullopt);
      continue;
    }
    std::optional<ParamValue> value = convert(spec, entry.value);
    bool ok = value.has_value();
    if (ok && (spec.type == ParamType::Int || spec.type == ParamType::Float)) {
      const double d =
          spec.type == ParamType::Int ? static_cast<double>(std::get<int64_t>(*value)) : std::get<double>(*value);
      if ((spec.min && d < *spec.min) || (spec.max && d > *spec.max)) ok = false;
    }
    if (ok && spec.type == ParamType::String && !spec.choices.empty()) {
      ok = std::find(spec.choices.begin(), spec.choices.end(), std::get<std::string>(*value)) != spec.choices.end();
    }
    if (!ok)
      fail("{}: {}.{} = {} is not valid: expected {}", entry.source, technique, spec.name,
           formatParamValue(entry.value), describeExpected(spec));
    params.set(spec.name, std::move(value));
  }
  return params;
}

const ParamValue& Params::find(const std::string& name) const {
  auto it = values_.find(name);
  if (it == values_.end()) fail("internal: parameter '{}' is not in the technique's schema", name);
  if (!it->second) fail("internal: parameter '{}' is \"auto\"; read it with getFloatOr or check isAuto first", name);
  return *it->second;
}

int64_t Params::getInt(const std::string& name) const { return std::get<int64_t>(find(name)); }
double Params::getFloat(const std::string& name) const {
  const ParamValue& v = find(name);
  if (auto* i = std::get_if<int64_t>(&v)) return static_cast<double>(*i);
  return std::get<double>(v);
}
bool Params::getBool(const std::string& name) const { return std::get<bool>(find(name)); }
const std::string& Params::getString(const std::string& name) const { return std::get<std::string>(find(name)); }
bool Params::isAuto(const std::string& name) const {
  auto it = values_.find(name);
  return it != values_.end() && !it->second;
}
double Params::getFloatOr(const std::string& name, double fallback) const {
  return isAuto(name) ? fallback : getFloat(name);
}

}  // namespace penumbra
