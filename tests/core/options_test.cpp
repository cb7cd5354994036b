// Tests of the one-declaration options (include/penumbra/options.h): the schema paramSchema() builds
// from an options struct (types from the members' C++ types, defaults from their initializers, a
// nested struct's parameters in place, "auto" for an empty optional, choices for named values), and
// optionsFromParams() reading resolved Params back into the struct.
#include <gtest/gtest.h>

#include "penumbra/options.h"

namespace penumbra {
namespace {

enum class Mode { Fast, Exact };

struct Inner {
  float gain = 0.1f;  // not a binary fraction: the schema must show 0.1, not 0.100000001490116
  static void describe(OptionFields<Inner>& f) { f.add(&Inner::gain, OptionDecl("gain").range(0, 1).help("gain")); }
};

struct Example {
  int kernel = 5;
  uint32_t seed = 7;
  double scale = 2.5;
  bool inner = true;
  std::string label = "box";
  std::optional<float> radius;  // auto
  Mode mode = Mode::Exact;
  Inner nested;

  static void describe(OptionFields<Example>& f) {
    f.add(&Example::kernel, OptionDecl("kernel").range(1, 63).unit("texels").help("kernel width"));
    f.nest(&Example::nested);
    f.add(&Example::seed, OptionDecl("seed").range(0, 4294967295.0));
    f.add(&Example::scale, OptionDecl("scale").range(0, 10));
    f.add(&Example::inner, OptionDecl("inner"));
    f.add(&Example::label, OptionDecl("label"));
    f.add(&Example::radius, OptionDecl("radius").range(1e-6, 1e6).unit("world units"));
    f.add(&Example::mode, OptionDecl("mode"), {{"fast", Mode::Fast}, {"exact", Mode::Exact}});
  }
};

TEST(Options, SchemaFromOneDeclaration) {
  const std::vector<ParamSpec> schema = paramSchema<Example>();
  ASSERT_EQ(schema.size(), 8u);
  // describe()'s order, the nested struct's parameters where it is nested.
  const char* names[] = {"kernel", "gain", "seed", "scale", "inner", "label", "radius", "mode"};
  for (size_t k = 0; k < schema.size(); ++k) EXPECT_EQ(schema[k].name, names[k]);

  EXPECT_EQ(schema[0].type, ParamType::Int);
  EXPECT_EQ(std::get<int64_t>(schema[0].defaultValue), 5);
  EXPECT_EQ(schema[0].min, 1.0);
  EXPECT_EQ(schema[0].max, 63.0);
  EXPECT_EQ(schema[0].unit, "texels");
  EXPECT_EQ(schema[0].help, "kernel width");

  EXPECT_EQ(schema[1].type, ParamType::Float);
  EXPECT_EQ(std::get<double>(schema[1].defaultValue), 0.1);  // the decimal the initializer was written with
  EXPECT_EQ(formatParamValue(schema[1].defaultValue), "0.1");

  EXPECT_EQ(schema[2].type, ParamType::Int);
  EXPECT_EQ(std::get<int64_t>(schema[2].defaultValue), 7);
  EXPECT_EQ(std::get<double>(schema[3].defaultValue), 2.5);
  EXPECT_EQ(schema[4].type, ParamType::Bool);
  EXPECT_EQ(std::get<bool>(schema[4].defaultValue), true);
  EXPECT_EQ(schema[5].type, ParamType::String);
  EXPECT_EQ(std::get<std::string>(schema[5].defaultValue), "box");

  EXPECT_EQ(schema[6].type, ParamType::Float);
  EXPECT_TRUE(schema[6].autoDefault);

  EXPECT_EQ(schema[7].type, ParamType::String);
  EXPECT_EQ(schema[7].choices, (std::vector<std::string>{"fast", "exact"}));
  EXPECT_EQ(std::get<std::string>(schema[7].defaultValue), "exact");
}

TEST(Options, ParsedFromResolvedParams) {
  // Defaults round-trip to the initializers, bit for bit (the float one too).
  const Example defaults = optionsFromParams<Example>(resolveParams("example", paramSchema<Example>(), {}));
  EXPECT_EQ(defaults.kernel, 5);
  EXPECT_EQ(defaults.nested.gain, 0.1f);
  EXPECT_EQ(defaults.seed, 7u);
  EXPECT_FALSE(defaults.radius.has_value());
  EXPECT_EQ(defaults.mode, Mode::Exact);

  ParamSet given;
  given.set("kernel", std::string("9"), "test");
  given.set("gain", 0.25, "test");
  given.set("seed", int64_t{4294967295}, "test");
  given.set("inner", false, "test");
  given.set("label", std::string("tent"), "test");
  given.set("radius", 0.5, "test");
  given.set("mode", std::string("fast"), "test");
  const Example o = optionsFromParams<Example>(resolveParams("example", paramSchema<Example>(), given));
  EXPECT_EQ(o.kernel, 9);
  EXPECT_EQ(o.nested.gain, 0.25f);
  EXPECT_EQ(o.seed, 4294967295u);
  EXPECT_EQ(o.scale, 2.5);
  EXPECT_FALSE(o.inner);
  EXPECT_EQ(o.label, "tent");
  ASSERT_TRUE(o.radius.has_value());
  EXPECT_EQ(*o.radius, 0.5f);
  EXPECT_EQ(o.mode, Mode::Fast);
}

}  // namespace
}  // namespace penumbra
