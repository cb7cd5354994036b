// The real-mesh corpus: every technique on the models people bring, not only on the built-in
// primitive scenes. Each scene of tests/corpus/ and each built-in real-mesh scene (wuson, engine,
// teapots) holds a model from Debian's assimp-testmodels fitted on a ground plane, under five lights:
// 0 rect, 1 disk, 2 sphere, 3 directional, 4 segment. Every technique runs on every light against
// the reference; the measurements are computed once per process and shared by the tests below.
//
// The bar for a soft technique, per scene and light it takes: RMSE8 below `hard`'s, no more umbra
// leaks (reference V < 0.05, V > 0.5) and no more speckle (ErrorStats::speckle) than `hard`, counts
// within a stated pixel margin. Where a technique misses it, kRecordedMisses records how often, with
// the paper's reason or as open work; the test fails when a technique misses more often than recorded
// and when a recorded miss no longer happens (so the record cannot go stale).
#include <algorithm>
#include <cstdio>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "penumbra/error.h"
#include "penumbra/gbuffer.h"
#include "penumbra/metrics.h"
#include "penumbra/raster.h"
#include "penumbra/reference.h"
#include "penumbra/registry.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

// 128^2 pixels and a 256-spp truth (standard error at most 0.031 in V, 0.016 where V < 0.07 or
// V > 0.93) keep the whole corpus near a minute on 2 cores; the techniques keep their defaults
// (1024^2 maps), as a user would run them.
constexpr int kImageSize = 128;
constexpr uint32_t kReferenceSpp = 256;

const std::vector<std::string>& corpusScenes() {
  static const std::vector<std::string> scenes = {
      "wuson",
      "engine",
      "teapots",
      PENUMBRA_SOURCE_DIR "/tests/corpus/spider.json",
      PENUMBRA_SOURCE_DIR "/tests/corpus/duck.json",
      PENUMBRA_SOURCE_DIR "/tests/corpus/jeep.json",
      PENUMBRA_SOURCE_DIR "/tests/corpus/rock.json",
      PENUMBRA_SOURCE_DIR "/tests/corpus/suzanne.json",
      PENUMBRA_SOURCE_DIR "/tests/corpus/sphere_with_hole.json",
      PENUMBRA_SOURCE_DIR "/tests/corpus/teapot_pair.json",
      PENUMBRA_SOURCE_DIR "/tests/corpus/gathering.json",
  };
  return scenes;
}

// The techniques the bar applies to (parker has its own test below: its paper puts the whole penumbra
// outside the hard shadow).
const std::vector<std::string> kSoft = {"pcf", "pcss", "multisample", "brabec", "plm", "smoothies",
                                        "kirsch", "heidrich", "ssv", "wedges"};

struct TechniqueRun {
  std::optional<ErrorStats> error;  //!< absent: the technique refused the light (`refusal` says why)
  std::string refusal;
  Image<float> v;
};

struct Case {
  std::string scene;  //!< the scene's name
  int light = 0;
  Image<uint8_t> mask;
  Image<float> reference;
  std::map<std::string, TechniqueRun> runs;  //!< by technique
};

bool sanitized() {
#if defined(__SANITIZE_ADDRESS__)
  return true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
  return true;
#endif
#endif
  return false;
}

// Every technique of the registry (but the reference and `none`) on every scene and light. Under the
// sanitizers, where everything runs several times slower, each scene keeps one of its lights (the
// lights taking turns over the scenes), so every light shape and every model is still seen.
const std::vector<Case>& corpus() {
  static const std::vector<Case> cases = [] {
    std::vector<Case> out;
    for (size_t s = 0; s < corpusScenes().size(); ++s) {
      const Scene scene = loadScene(corpusScenes()[s]);
      const GBuffer gbuffer = renderGBuffer(scene, kImageSize, kImageSize);
      for (int l = 0; l < static_cast<int>(scene.lights.size()); ++l) {
        if (sanitized() && l != static_cast<int>(s % scene.lights.size())) continue;
        const Light& light = scene.lights[l];
        Case c;
        c.scene = scene.name;
        c.light = l;
        c.mask = errorMask(gbuffer, light);
        ReferenceTechnique reference(ReferenceOptions{kReferenceSpp, 1});
        reference.prepare(scene, light);
        reference.visibility(gbuffer, c.reference);
        for (const TechniqueInfo& info : techniqueRegistry()) {
          if (info.name == "reference" || info.name == "none") continue;
          TechniqueRun run;
          try {
            auto technique = createTechnique(info.name);
            technique->prepare(scene, light);
            technique->visibility(gbuffer, run.v);
            run.error = compareVisibility(run.v, c.reference, c.mask);
          } catch (const Error& e) {
            run.refusal = e.what();
          }
          c.runs.emplace(info.name, std::move(run));
        }
        out.push_back(std::move(c));
      }
    }
    return out;
  }();
  return cases;
}

std::string label(const Case& c) { return fmt::format("{}/light {}", c.scene, c.light); }

// A technique may refuse a light only for its shape, never for a model.
TEST(RealMeshCorpus, EveryTechniqueRunsOrRefusesOnlyTheLightShape) {
  const std::set<std::string> shapes = {"sphere", "disk", "rect", "segment", "polygon", "directional"};
  for (const Case& c : corpus()) {
    for (const auto& [name, run] : c.runs) {
      if (run.error) continue;
      SCOPED_TRACE(label(c) + " " + name);
      bool namesAShape = false;
      for (const std::string& shape : shapes) namesAShape = namesAShape || run.refusal.find("a " + shape + " light") != std::string::npos;
      EXPECT_TRUE(namesAShape) << run.refusal;
      EXPECT_EQ(run.refusal.find("object '"), std::string::npos) << "refused for a model: " << run.refusal;
    }
  }
}

// Pixel counts are compared with a margin: at 128^2 the shadow-map techniques disagree with one
// another by a few pixels along contact lines and one-pixel shadow lines of thin parts, where the
// umbra's or the line's edge passes between pixel centres. The margin is stated once, here: a count
// may exceed hard's by max(3 pixels, 10% of hard's count).
bool withinCountMargin(size_t count, size_t hardCount) { return count <= std::max<size_t>(hardCount + 3, hardCount + hardCount / 10); }

// The bar's misses measured on the whole corpus, per technique and measure: the test fails when a
// technique misses more cases than recorded here (a regression) and, on the full corpus, when it
// misses none (the record is stale and must go). Each is open work unless its paper explains it.
struct RecordedMisses {
  const char* technique;
  const char* measure;  //!< "rmse8", "umbra leaks" or "speckle"
  size_t cases;         //!< of 55 scene/light cases (44 for techniques that refuse segment lights)
  const char* why;
};
const RecordedMisses kRecordedMisses[] = {
    {"smoothies", "rmse8", 43,
     "outer penumbra only (Chan and Durand 2003): it keeps the hard shadow whole and fades outwards, so it only "
     "trades the hard edge's error outside for error inside; Lawlor's Fig. 10 puts it below the hard shadow map, "
     "which we do not reproduce on real meshes (open)"},
    {"smoothies", "speckle", 7, "open"},
    {"kirsch", "rmse8", 37,
     "inner penumbra only (Kirsch and Doellner 2003): the hard shadow's outline stays the shadow's outer border, "
     "so half of every penumbra is missing; Lawlor's Fig. 10 puts it below the hard shadow map (open)"},
    {"kirsch", "umbra leaks", 18, "open: its fade from the hard edge inwards lights umbra pixels near thin parts"},
    {"kirsch", "speckle", 13, "open"},
    {"pcf", "speckle", 23,
     "Reeves' filter over a box fixed in texels, blind to the light and the occluder distance: no width meets "
     "the bar on 9 of the cases even when chosen per case (1 to 25 texels), and the best single width (7) "
     "misses speckle on 18 and umbra leaks on 14; its extra specks are mostly lit pixels beside a rising "
     "surface (a concave crease, a wall next to the receiver) that the box's receiver-plane compares count "
     "as a blocker"},
    {"pcf", "umbra leaks", 1, "the fixed box blurs the umbra of jeep's segment light (every width from 3 to 9 texels)"},
    {"pcss", "speckle", 8,
     "open: not the tap counts (32 or 64 search taps, 64 filter taps: 8 or 9 misses); the extra specks are "
     "umbra pixels the filter lightens and lit pixels beside a rising surface that the filter's "
     "receiver-plane compares count as a blocker"},
    {"multisample", "speckle", 2,
     "16 light samples of one fixed pattern: V moves in steps of 1/16 and the specks follow the pattern "
     "(engine, disk light: 15, 23, 12 for seeds 1, 2, 3; hard 11)"},
    {"plm", "speckle", 5,
     "open: most extra specks lie where hard leaks (reference umbra, centre map lit) and plm darkens only "
     "part of it; with a 2048^2 map 4 of the 5 cases meet the bar"},
    {"heidrich", "speckle", 3,
     "the slides' 'Undersampling artifacts: regions where portions of the light source are visible, but none "
     "of the end points!' at the default two sample points; their remedy, subdivisions = 4, meets the bar "
     "on every case at 3.8x the default's frame time (engine, 1024^2)"},
    {"ssv", "speckle", 1,
     "open: on duck's rect light V drops to 0 on single pixels of a smooth penumbra where a silhouette cut "
     "at p does not wind around the light's centre, the centre ray meets its object, and the side fix then "
     "loops it around the whole light square"},
};

TEST(RealMeshCorpus, SoftTechniquesBeatHardWithoutLeaksOrSpeckle) {
  std::string table = "scene/light technique: RMSE8 (hard) / umbra leaks (hard) / speckle (hard)\n";
  std::map<std::pair<std::string, std::string>, size_t> misses;
  for (const Case& c : corpus()) {
    const TechniqueRun& hard = c.runs.at("hard");
    ASSERT_TRUE(hard.error) << label(c) << ": " << hard.refusal;
    for (const std::string& name : kSoft) {
      const TechniqueRun& run = c.runs.at(name);
      if (!run.error) continue;
      const ErrorStats& e = *run.error;
      const ErrorStats& h = *hard.error;
      table += fmt::format("{} {}: {:.2f} ({:.2f}) / {} ({}) / {} ({})\n", label(c), name, e.rmse8, h.rmse8,
                           e.umbraLeaks, h.umbraLeaks, e.speckle, h.speckle);
      if (!(e.rmse8 < h.rmse8)) ++misses[{name, "rmse8"}];
      if (!withinCountMargin(e.umbraLeaks, h.umbraLeaks)) ++misses[{name, "umbra leaks"}];
      if (!withinCountMargin(e.speckle, h.speckle)) ++misses[{name, "speckle"}];
    }
  }
  std::fputs(table.c_str(), stdout);
  for (const RecordedMisses& r : kRecordedMisses) {
    const size_t measured = misses[{r.technique, r.measure}];
    std::printf("[ measured ] %s misses the bar on %s in %zu cases (recorded %zu)\n", r.technique, r.measure, measured,
                r.cases);
    EXPECT_LE(measured, r.cases) << r.technique << " " << r.measure << ": more misses than recorded (" << r.why << ")";
    if (!sanitized())
      EXPECT_GT(measured, 0u) << r.technique << " " << r.measure << " meets the bar everywhere now: drop the record";
  }
  for (const auto& [key, count] : misses) {
    bool known = false;
    for (const RecordedMisses& r : kRecordedMisses) known = known || (key.first == r.technique && key.second == r.measure);
    EXPECT_TRUE(known || count == 0) << key.first << " misses the bar on " << key.second << " in " << count << " cases";
  }
}

// parker (Parker, Shirley and Smits 1998) keeps each object as its own inner object, so its shadow is
// the exact hard shadow widened outwards: "the umbra region will be larger than in a physically-based
// computation". Its claims on real models: wherever the exact hard shadow is dark, parker is dark (no
// light leaks), and nowhere is it brighter than the exact hard shadow (the penumbra lies outside it).
TEST(RealMeshCorpus, ParkerDarkensOnlyOutsideTheHardShadowAndNeverLeaks) {
  for (const Case& c : corpus()) {
    const TechniqueRun& parker = c.runs.at("parker");
    const TechniqueRun& hard = c.runs.at("raytraced-hard");
    if (!parker.error) continue;
    SCOPED_TRACE(label(c));
    size_t brighter = 0, leaks = 0;
    for (size_t i = 0; i < parker.v.size(); ++i) {
      if (!c.mask[i]) continue;
      if (parker.v[i] > hard.v[i] + 1e-5f) ++brighter;
      if (hard.v[i] == 0.0f && parker.v[i] > 0.0f) ++leaks;
    }
    EXPECT_EQ(brighter, 0u);
    EXPECT_EQ(leaks, 0u);
    EXPECT_EQ(parker.error->umbraLeaks, 0u);
  }
}

}  // namespace
}  // namespace penumbra
