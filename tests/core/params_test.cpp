// Tests of parameter validation (src/core/params.cpp): resolveParams fills defaults, converts
// command-line strings and JSON values, keeps "auto", and rejects unknown names (listing the known
// ones), wrong types and out-of-range values with the source, the parameter and what was expected.
#include <gtest/gtest.h>

#include "penumbra/error.h"
#include "penumbra/params.h"

namespace penumbra {
namespace {

std::vector<ParamSpec> schema() {
  return {
      ParamSpec{.name = "kernel",
                .type = ParamType::Int,
                .defaultValue = int64_t{5},
                .min = 1.0,
                .max = 63.0,
                .choices = {},
                .unit = "texels",
                .help = "kernel width"},
      ParamSpec{.name = "r_scale",
                .type = ParamType::Float,
                .defaultValue = 0.5,
                .min = 0.0,
                .max = std::nullopt,
                .choices = {},
                .unit = "",
                .help = "radius scale",
                .autoDefault = true},
      ParamSpec{.name = "bias",
                .type = ParamType::Float,
                .defaultValue = 0.01,
                .min = 0.0,
                .max = 1.0,
                .choices = {},
                .unit = "world units",
                .help = "depth bias"},
      ParamSpec{.name = "inner",
                .type = ParamType::Bool,
                .defaultValue = true,
                .min = std::nullopt,
                .max = std::nullopt,
                .choices = {},
                .unit = "",
                .help = "inner penumbra"},
      ParamSpec{.name = "filter",
                .type = ParamType::String,
                .defaultValue = std::string("box"),
                .min = std::nullopt,
                .max = std::nullopt,
                .choices = {"box", "tent"},
                .unit = "",
                .help = "filter"},
  };
}

std::string errorOf(const ParamSet& given) {
  try {
    resolveParams("pcf", schema(), given);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(Params, DefaultsAndAuto) {
  const Params p = resolveParams("pcf", schema(), {});
  EXPECT_EQ(p.getInt("kernel"), 5);
  EXPECT_TRUE(p.isAuto("r_scale"));  // autoDefault: "auto" unless given
  EXPECT_DOUBLE_EQ(p.getFloatOr("r_scale", 0.75), 0.75);
  EXPECT_DOUBLE_EQ(p.getFloat("bias"), 0.01);
  EXPECT_TRUE(p.getBool("inner"));
  EXPECT_EQ(p.getString("filter"), "box");
  EXPECT_DOUBLE_EQ(p.getFloat("kernel"), 5.0);  // an Int reads as a Float too
  EXPECT_THROW(p.getFloat("r_scale"), Error);   // "auto" must be read with getFloatOr
  EXPECT_THROW(p.getInt("nonexistent"), Error);
}

TEST(Params, AcceptsCommandLineStringsAndJsonValues) {
  ParamSet given;
  given.setFromKeyValue("kernel=9", "command line");
  given.setFromKeyValue("r_scale=1.5", "command line");
  given.set("bias", int64_t{1}, "scene.json: techniques.pcf.bias");  // a JSON integer for a Float
  given.setFromKeyValue("inner=off", "command line");
  given.setFromKeyValue("filter=tent", "command line");
  const Params p = resolveParams("pcf", schema(), given);
  EXPECT_EQ(p.getInt("kernel"), 9);
  EXPECT_FALSE(p.isAuto("r_scale"));
  EXPECT_DOUBLE_EQ(p.getFloatOr("r_scale", 0.75), 1.5);
  EXPECT_DOUBLE_EQ(p.getFloat("bias"), 1.0);
  EXPECT_FALSE(p.getBool("inner"));
  EXPECT_EQ(p.getString("filter"), "tent");
  // A JSON 3.0 is an integer; "auto" is accepted where the default is auto.
  ParamSet more;
  more.set("kernel", 3.0, "scene.json");
  more.set("r_scale", std::string("auto"), "scene.json");
  const Params q = resolveParams("pcf", schema(), more);
  EXPECT_EQ(q.getInt("kernel"), 3);
  EXPECT_TRUE(q.isAuto("r_scale"));
  // Later values replace earlier ones (the command line overrides the scene file).
  ParamSet both;
  both.set("kernel", int64_t{7}, "scene.json");
  both.setFromKeyValue("kernel=11", "command line");
  EXPECT_EQ(resolveParams("pcf", schema(), both).getInt("kernel"), 11);
}

TEST(Params, UnknownNameListsTheKnownOnes) {
  ParamSet given;
  given.setFromKeyValue("kernal=3", "command line");
  const std::string msg = errorOf(given);
  EXPECT_NE(msg.find("command line"), std::string::npos) << msg;
  EXPECT_NE(msg.find("'kernal'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("kernel, r_scale, bias, inner, filter"), std::string::npos) << msg;
  // A technique without parameters says so.
  try {
    resolveParams("none", {}, given);
    ADD_FAILURE() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("none"), std::string::npos) << e.what();
  }
}

TEST(Params, RejectsOutOfRangeAndWrongTypes) {
  struct Case {
    std::string name;
    ParamValue value;
    std::string expected;  // a fragment of the message
  };
  const std::vector<Case> cases = {
      {"kernel", int64_t{0}, "int in [1, 63]"},
      {"kernel", int64_t{64}, "int in [1, 63]"},
      {"kernel", 2.5, "int in [1, 63]"},
      {"kernel", std::string("3x"), "int in [1, 63]"},
      {"kernel", true, "int in [1, 63]"},
      {"r_scale", -0.1, "float >= 0 or \"auto\""},
      {"r_scale", std::string("nan"), "float >= 0"},
      {"bias", std::string("auto"), "float in [0, 1]"},  // not an auto parameter
      {"bias", std::string("inf"), "float in [0, 1]"},
      {"inner", std::string("maybe"), "bool"},
      {"inner", int64_t{1}, "bool"},
      {"filter", std::string("gauss"), "one of box, tent"},
      {"filter", 2.0, "string"},
  };
  for (const Case& c : cases) {
    ParamSet given;
    given.set(c.name, c.value, "scene.json: techniques.pcf." + c.name);
    const std::string msg = errorOf(given);
    SCOPED_TRACE(::testing::Message() << c.name << " = " << formatParamValue(c.value) << ": " << msg);
    EXPECT_NE(msg.find("scene.json: techniques.pcf." + c.name), std::string::npos);
    EXPECT_NE(msg.find("pcf." + c.name + " = " + formatParamValue(c.value)), std::string::npos);
    EXPECT_NE(msg.find(c.expected), std::string::npos);
  }
  // The bounds are inclusive.
  ParamSet edge;
  edge.set("kernel", int64_t{63}, "test");
  edge.set("bias", 0.0, "test");
  EXPECT_NO_THROW(resolveParams("pcf", schema(), edge));
}

TEST(Params, KeyValueSyntax) {
  ParamSet s;
  EXPECT_THROW(s.setFromKeyValue("kernel", "command line"), Error);
  EXPECT_THROW(s.setFromKeyValue("=3", "command line"), Error);
  s.setFromKeyValue("filter=a=b", "command line");  // the value may hold '='
  EXPECT_EQ(std::get<std::string>(s.entries().at("filter").value), "a=b");
  EXPECT_TRUE(s.has("filter"));
  EXPECT_FALSE(s.has("kernel"));
}

}  // namespace
}  // namespace penumbra
