// A technique's options, declared once (docs/architecture.md, "The registry"). An options struct
// holds one member per parameter, its initializer being the default, and a static describe() that
// binds each member to its parameter's name, range, unit and help:
//
//   struct PcfOptions {
//     int mapSize = 1024;
//     int kernel = 3;
//     DepthBias bias;
//     static void describe(OptionFields<PcfOptions>& f) {
//       f.add(&PcfOptions::mapSize, mapSizeOption());  // shared with every shadow-map technique
//       f.add(&PcfOptions::kernel, OptionDecl("kernel").range(1, 63).unit("texels").help("..."));
//       f.nest(&PcfOptions::bias);                    // DepthBias::describe: bias_constant, bias_slope
//     }
//   };
//
// From that declaration come the schema, paramSchema<PcfOptions>() (ParamSpecs in describe()'s order,
// the type from the member's C++ type, the default from its initializer), and the parsing of resolved
// Params into the struct, optionsFromParams<PcfOptions>(). Member types and what they map to:
//   integers -> Int; float, double -> Float; bool -> Bool; std::string -> String;
//   std::optional<float or double> -> Float with the default "auto" (empty: the technique derives it);
//   any type with a list of named values (an enum; add()'s third argument) -> String with those choices.
// A check that is not a range (pcf's odd kernel) stays in the technique's constructor, naming the field.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "penumbra/params.h"

namespace penumbra {

// A parameter's name, inclusive range, unit and help: all of its schema entry but the type and the
// default, which come from the member it is bound to.
struct OptionDecl {
  explicit OptionDecl(std::string name) : name(std::move(name)) {}
  OptionDecl range(double lo, double hi) && {
    min = lo;
    max = hi;
    return std::move(*this);
  }
  OptionDecl unit(std::string text) && {
    unitText = std::move(text);
    return std::move(*this);
  }
  OptionDecl help(std::string text) && {
    helpText = std::move(text);
    return std::move(*this);
  }

  std::string name;
  std::optional<double> min, max;
  std::string unitText, helpText;
};

namespace detail {
// A float default as the double its shortest decimal form reads as (0.01f -> 0.01, not
// 0.009999999776...), so that the schema shows the number the initializer was written with.
double decimalDouble(float value);

template <class T>
struct IsOptional : std::false_type {};
template <class T>
struct IsOptional<std::optional<T>> : std::true_type {};
}  // namespace detail

template <class Options>
class OptionFields {
 public:
  struct Field {
    ParamSpec spec;
    std::function<void(Options&, const Params&)> read;               //!< sets the member from resolved Params
    std::function<std::optional<ParamValue>(const Options&)> value;  //!< the member's value; empty: "auto"
  };

  // Binds `member` to the parameter `decl`.
  template <class T>
  void add(T Options::*member, OptionDecl decl) {
    Field field{specOf(std::move(decl)), {}, {}};
    const std::string name = field.spec.name;
    if constexpr (std::is_same_v<T, bool>) {
      field.spec.type = ParamType::Bool;
      field.read = [=](Options& o, const Params& p) { o.*member = p.getBool(name); };
      field.value = [=](const Options& o) { return std::optional<ParamValue>(o.*member); };
    } else if constexpr (std::is_integral_v<T>) {
      field.spec.type = ParamType::Int;
      field.read = [=](Options& o, const Params& p) { o.*member = static_cast<T>(p.getInt(name)); };
      field.value = [=](const Options& o) { return std::optional<ParamValue>(static_cast<int64_t>(o.*member)); };
    } else if constexpr (std::is_floating_point_v<T>) {
      field.spec.type = ParamType::Float;
      field.read = [=](Options& o, const Params& p) { o.*member = static_cast<T>(p.getFloat(name)); };
      field.value = [=](const Options& o) { return std::optional<ParamValue>(toDouble(o.*member)); };
    } else if constexpr (std::is_same_v<T, std::string>) {
      field.spec.type = ParamType::String;
      field.read = [=](Options& o, const Params& p) { o.*member = p.getString(name); };
      field.value = [=](const Options& o) { return std::optional<ParamValue>(o.*member); };
    } else if constexpr (detail::IsOptional<T>::value && std::is_floating_point_v<typename T::value_type>) {
      using U = typename T::value_type;
      // Declared empty: the default is "auto", derived by the technique (ParamSpec::autoDefault).
      field.spec.type = ParamType::Float;
      field.spec.autoDefault = true;
      field.read = [=](Options& o, const Params& p) {
        o.*member = p.isAuto(name) ? std::nullopt : std::optional<U>(static_cast<U>(p.getFloat(name)));
      };
      field.value = [=](const Options& o) {
        return (o.*member) ? std::optional<ParamValue>(toDouble(*(o.*member))) : std::nullopt;
      };
    } else {
      static_assert(sizeof(T) == 0, "an option of this type needs named values: add(member, decl, choices)");
    }
    push(std::move(field));
  }

  // Binds `member` to a String parameter whose values are the names of `choices`, in that order.
  template <class T>
  void add(T Options::*member, OptionDecl decl, std::vector<std::pair<std::string, T>> choices) {
    Field field{specOf(std::move(decl)), {}, {}};
    field.spec.type = ParamType::String;
    for (const auto& choice : choices) field.spec.choices.push_back(choice.first);
    const std::string name = field.spec.name;
    field.read = [=](Options& o, const Params& p) {
      for (const auto& [choiceName, value] : choices)
        if (choiceName == p.getString(name)) o.*member = value;
    };
    field.value = [=](const Options& o) {
      for (const auto& [choiceName, value] : choices)
        if (value == o.*member) return std::optional<ParamValue>(choiceName);
      return std::optional<ParamValue>(std::string());
    };
    push(std::move(field));
  }

  // Binds the parameters of a nested options struct, declared by its own describe(): the ones
  // several techniques share, such as DepthBias.
  template <class Nested>
  void nest(Nested Options::*member) {
    OptionFields<Nested> nested;
    Nested::describe(nested);
    for (const auto& inner : nested.fields()) {
      Field field{inner.spec, {}, {}};
      field.read = [member, read = inner.read](Options& o, const Params& p) { read(o.*member, p); };
      field.value = [member, value = inner.value](const Options& o) { return value(o.*member); };
      // The default is the outer struct's, should it initialize the nested one differently.
      push(std::move(field));
    }
  }

  const std::vector<Field>& fields() const { return fields_; }

 private:
  static ParamSpec specOf(OptionDecl decl) {
    ParamSpec spec;
    spec.name = std::move(decl.name);
    spec.min = decl.min;
    spec.max = decl.max;
    spec.unit = std::move(decl.unitText);
    spec.help = std::move(decl.helpText);
    return spec;
  }
  static double toDouble(float value) { return detail::decimalDouble(value); }
  static double toDouble(double value) { return value; }
  void push(Field field) {
    // The default is the member's initializer ("auto" keeps ParamSpec's placeholder 0).
    field.spec.defaultValue = field.value(Options{}).value_or(ParamValue(0.0));
    fields_.push_back(std::move(field));
  }

  std::vector<Field> fields_;
};

// The fields of Options::describe(), built once.
template <class Options>
const OptionFields<Options>& optionFields() {
  static const OptionFields<Options> fields = [] {
    OptionFields<Options> f;
    Options::describe(f);
    return f;
  }();
  return fields;
}

// The schema of Options: one ParamSpec per declared parameter, in describe()'s order.
template <class Options>
std::vector<ParamSpec> paramSchema() {
  std::vector<ParamSpec> specs;
  for (const auto& field : optionFields<Options>().fields()) specs.push_back(field.spec);
  return specs;
}

// Options from Params resolved against paramSchema<Options>() (every parameter present, validated).
template <class Options>
Options optionsFromParams(const Params& params) {
  Options options;
  for (const auto& field : optionFields<Options>().fields()) field.read(options, params);
  return options;
}

// Checks every member of `options` against its declaration (range, choices) exactly as the registry
// checks parameters given by name (resolveParams): throws Error naming the technique and the parameter.
// The typed factories (makeTechnique) call it, so a struct filled by hand is held to the same ranges.
template <class Options>
void validateOptions(const std::string& technique, const Options& options) {
  ParamSet given;
  for (const auto& field : optionFields<Options>().fields())
    if (const std::optional<ParamValue> value = field.value(options))
      given.set(field.spec.name, *value, "the options struct");
  resolveParams(technique, paramSchema<Options>(), given);
}

}  // namespace penumbra
