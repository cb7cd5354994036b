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
// and when a recorded miss no longer happens (so the record cannot go stale). smoothies and kirsch,
// which draw one half of the penumbra each, are also held to their paper's comparison: against their
// half of the truth (Lawlor 2006, Fig. 11), below `hard` against the same half.
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
// (1024^2 maps; `horizon` facing for pcf, pcss, plm, smoothies and kirsch, off for hard), as a user would run
// them.
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
const std::vector<std::string> kSoft = {"pcf",       "pcss",   "multisample", "brabec", "plm",
                                        "smoothies", "kirsch", "heidrich",    "ssv",    "wedges"};

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
      for (const std::string& shape : shapes)
        namesAShape = namesAShape || run.refusal.find("a " + shape + " light") != std::string::npos;
      EXPECT_TRUE(namesAShape) << run.refusal;
      EXPECT_EQ(run.refusal.find("object '"), std::string::npos) << "refused for a model: " << run.refusal;
    }
  }
}

// Pixel counts are compared with a margin: at 128^2 the shadow-map techniques disagree with one
// another by a few pixels along contact lines and one-pixel shadow lines of thin parts, where the
// umbra's or the line's edge passes between pixel centres. The margin is stated once, here: a count
// may exceed hard's by max(3 pixels, 10% of hard's count).
bool withinCountMargin(size_t count, size_t hardCount) {
  return count <= std::max<size_t>(hardCount + 3, hardCount + hardCount / 10);
}

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
    {"smoothies", "rmse8", 21,
     "outer penumbra only (Chan and Durand 2003): Lawlor 2006 measures it against the outer half, \"they only compute "
     "one half of the penumbra\" (Fig. 10; Fig. 11: \"compared with the outer and inner penumbra respectively\"); "
     "against the full truth its fade from 0 at the hard edge, where the truth is 1/2, moves hard's error inwards. "
     "Against its half it beats hard (HalfPenumbraTechniquesBeatHardAgainstTheirHalf)"},
    {"kirsch", "rmse8", 15,
     "inner penumbra only (Kirsch and Doellner 2003): Lawlor 2006 measures it against the inner half, \"they only "
     "compute one half of the penumbra\" (Fig. 10; Fig. 11: \"compared with the outer and inner penumbra "
     "respectively\"). Against its half it beats hard (HalfPenumbraTechniquesBeatHardAgainstTheirHalf)"},
    {"kirsch", "umbra leaks", 3,
     "method (engine lights 0 and 3, duck 2; 18 cases with horizon off and the texel-centre width): its attenuation "
     "takes \"the "
     "distance of the occluding point to the shadowed point\" (Kirsch and "
     "Doellner's abstract), the depth map's point over the pixel; on a rounded occluder that is its top, nearer the "
     "light than the silhouette that bounds the shadow, so the fade is too wide and reaches into the umbra (\"The "
     "shadow-casting surfaces, however, should satisfy a few geometric properties to prevent artifacts\"); 200 of "
     "the 299 pixels where it leaked and hard did not (horizon off) fall to V <= 0.5 with the silhouette edge's depth "
     "(docs/real-meshes.md)"},
    {"kirsch", "speckle", 2,
     "method (engine 2, suzanne 2): the hard map's isolated lit texels stay lit (outside the hard shadow V = 1), and "
     "dark pixels are left alone in the too-wide fade of its umbra leaks; with horizon off and the texel-centre "
     "width (13 cases), 217 of its 505 specks on the corpus lay on pixels where hard has one"},
    {"pcf", "speckle", 16,
     "Reeves' filter over a box fixed in texels, blind to the light and the occluder distance (measured with horizon "
     "off, 23 cases then): no width meets "
     "the bar on 9 of the cases even when chosen per case (1 to 25 texels), and the best single width (7) "
     "misses speckle on 18 and umbra leaks on 14; its extra specks are mostly lit pixels beside a rising "
     "surface (a concave crease, a wall next to the receiver) that the box's receiver-plane compares count "
     "as a blocker"},
    {"pcss", "speckle", 4,
     "method (engine 0, 2 and 4, suzanne 4): PCSS (Fernando 2005) reads the one shadow map seen from "
     "the light's centre, averages the depths of "
     "the texels in front of the receiver and sizes its filter from that mean by similar triangles, as if blocker "
     "and receiver were parallel planes. Counted with horizon off, in the 8 cases it then missed: of its 146 specks "
     "(hard: 75), 78 lie in the reference's umbra, 55 of them beside a pixel where hard leaks or "
     "speckles (the filter reads the same centre map and spreads its misses over part of their neighbours); 35 are lit "
     "pixels on a "
     "crease or beside a rising surface, whose texels a texel away lie closer than the receiver plane (filter "
     "radius under a texel); 32 lie in smooth penumbrae. Not the tap counts (32 or 64 search taps, 64 filter "
     "taps: 8 or 9 misses), nor the mean depth (the deepest blocker instead: 9 misses)"},
    {"multisample", "speckle", 2,
     "16 light samples of one fixed pattern: V moves in steps of 1/16 and the specks follow the pattern "
     "(engine, disk light: 15, 23, 12 for seeds 1, 2, 3; hard 11)"},
    {"plm", "speckle", 2,
     "open (engine 0 and 2): not the plain map's resolution. Counted with horizon off, in the 5 cases it "
     "then missed: all 120 specks (hard: 71, 32 shared) lie on texels "
     "under a ribbon. 86 lie in the reference's umbra, 27 in its penumbra, 7 where it is lit; 67 are right "
     "themselves (error <= 0.25) and count because neighbours are wrong; 91 lie within a pixel of a hard leak; 76 "
     "fetches straddle two or more edges, 44 one (69 take Equation 2 per texel). In 43 the pixel or a wrong "
     "neighbour has a texel where the depth bias alone lifts a receiver below the edge above the occluder's top "
     "(zc < g <= c < z), under the same mesh (the slope-scaled bias of a grazing receiver spans several texels): "
     "lifting it no higher than c where g lies a texel above c cuts engine's specks to 18, 14, 16 (leaks 15, 14 -> "
     "8, 8), but darkens receivers near their own silhouette (speckle up on rock, suzanne, wuson; RMSE8 up on "
     "wuson and gathering). The paper reports the same two faults on its bunny (Fig. 8: \"self-shadowing errors\" "
     "and \"silhouette leakage\")"},
    {"heidrich", "speckle", 3,
     "the slides' 'Undersampling artifacts: regions where portions of the light source are visible, but none "
     "of the end points!' at the default two sample points; their remedy, subdivisions = 4, meets the bar "
     "on every case at 3.8x the default's frame time (engine, 1024^2)"},
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
    if (!sanitized()) {
      EXPECT_GT(measured, 0u) << r.technique << " " << r.measure << " meets the bar everywhere now: drop the record";
    }
  }
  for (const auto& [key, count] : misses) {
    bool known = false;
    for (const RecordedMisses& r : kRecordedMisses)
      known = known || (key.first == r.technique && key.second == r.measure);
    EXPECT_TRUE(known || count == 0) << key.first << " misses the bar on " << key.second << " in " << count << " cases";
  }
}

// smoothies (Chan and Durand 2003) and kirsch (Kirsch and Doellner 2003) each draw one half of the
// penumbra, and Lawlor 2006 measures them so: "Smoothies and Kirsch and Döllner are compared with the
// outer and inner penumbra respectively" (Fig. 11). Against its half truth (halfPenumbraTruth,
// metrics.h), each must beat `hard` measured against the same half truth, on every case it takes, but
// for the cases named in kHalfPenumbraMisses, which must keep missing (so the record cannot go stale).
struct HalfPenumbraMiss {
  const char* technique;
  const char* label;  //!< "scene/light N"
  const char* why;
};
const HalfPenumbraMiss kHalfPenumbraMisses[] = {
    // Measured (RMSE8 against the outer half truth, smoothies / hard): light 0 41.50 / 30.84, light 1
    // 37.35 / 29.74 (light 2 27.22 / 28.51 and light 3 15.48 / 18.99 pass).
    {"smoothies", "teapots/light 0",
     "the outer half-penumbra model puts V = 1/2 at the hard edge (Lawlor, Sec. 2: a half-infinite occluder); "
     "teapots floating under a light wider than they are leave most of the light visible at their hard edge "
     "(docs/small-occluders.md), and the fade from 0 there is darker than the truth by more than hard's 1 is too "
     "bright"},
    {"smoothies", "teapots/light 1", "as light 0: the disk light of radius 1.2 is wider than the teapots"},
};

TEST(RealMeshCorpus, HalfPenumbraTechniquesBeatHardAgainstTheirHalf) {
  const std::pair<const char*, PenumbraHalf> kHalves[] = {{"smoothies", PenumbraHalf::Outer},
                                                          {"kirsch", PenumbraHalf::Inner}};
  std::string table = "scene/light technique: RMSE8 / umbra leaks / speckle against its half truth (hard's)\n";
  for (const auto& [name, half] : kHalves) {
    size_t misses = 0, cases = 0;
    for (const Case& c : corpus()) {
      const TechniqueRun& run = c.runs.at(name);
      if (!run.error) continue;
      const Image<float> truth = halfPenumbraTruth(c.reference, half);
      const ErrorStats e = compareVisibility(run.v, truth, c.mask);
      const ErrorStats h = compareVisibility(c.runs.at("hard").v, truth, c.mask);
      table += fmt::format("{} {}: {:.2f} ({:.2f}) / {} ({}) / {} ({})\n", label(c), name, e.rmse8, h.rmse8,
                           e.umbraLeaks, h.umbraLeaks, e.speckle, h.speckle);
      ++cases;
      const bool beats = e.rmse8 < h.rmse8;
      misses += beats ? 0 : 1;
      const HalfPenumbraMiss* recorded = nullptr;
      for (const HalfPenumbraMiss& m : kHalfPenumbraMisses)
        if (name == std::string(m.technique) && label(c) == m.label) recorded = &m;
      if (recorded)
        EXPECT_FALSE(beats) << label(c) << " " << name << " beats hard against its half truth now: drop the record";
      else
        EXPECT_TRUE(beats) << label(c) << " " << name << " against its half truth: " << e.rmse8 << ", hard " << h.rmse8;
    }
    std::printf("[ measured ] %s against its half truth misses in %zu of %zu cases\n", name, misses, cases);
  }
  std::fputs(table.c_str(), stdout);
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
