// Tests of `none` (src/techniques/none.cpp): V = 1 on every pixel, even under an occluder, sized
// like the G-buffer; no parameters.
#include <gtest/gtest.h>

#include "penumbra/error.h"
#include "penumbra/registry.h"
#include "rt/rt_test_scenes.h"

namespace penumbra {
namespace {

TEST(None, VisibilityIsOneEverywhere) {
  auto t = createTechnique("none");
  EXPECT_EQ(t->name(), "none");
  const Scene scene =
      testing::makeScene({testing::makeObject(1, testing::quadMesh(Vec3(0, 0, 2), Vec3(5, 0, 0), Vec3(0, 5, 0)))});
  t->prepare(scene, Light::disk(Vec3(0, 0, 4), Vec3(0, 0, 1), 0.5f));
  GBuffer g = testing::pointsGBuffer({Vec3(0.0f), Vec3(1.0f, 0.0f, 0.0f), Vec3(0.0f)}, Vec3(0, 0, 1), 2);
  g.objectId(2, 0) = kNoObject;
  Image<float> v(1, 1, 0.0f);
  t->visibility(g, v);
  ASSERT_EQ(v.width(), 3);
  ASSERT_EQ(v.height(), 1);
  for (float x : v) EXPECT_EQ(x, 1.0f);
  EXPECT_EQ(t->timings().passes.size(), 2u);
  EXPECT_TRUE(findTechnique("none").params.empty());
  ParamSet extra;
  extra.set("spp", int64_t{4}, "test");
  EXPECT_THROW(createTechnique("none", extra), Error);
}

}  // namespace
}  // namespace penumbra
