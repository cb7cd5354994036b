// The silhouette-ribbon family's typed options and factories (docs/techniques.md): plm (Lawlor 2006),
// smoothies (Chan & Durand 2003) and kirsch (Kirsch & Döllner 2003) as rows of Lawlor's table. See
// shadow_map.h of this folder for how options and factories are used.
#pragma once

#include <memory>

#include "penumbra/options.h"
#include "penumbra/technique.h"
#include "penumbra/techniques/shadow_map.h"

namespace penumbra {

// Parameters shared by the ribbon techniques (plm, smoothies, kirsch), declared once (options.h).
inline OptionDecl ribbonMarginOption() {
  return OptionDecl("margin").range(0, 64).unit("texels").help(
      "added to every silhouette ribbon's half-width, so bilinear lookups near a penumbra read one ribbon");
}
inline OptionDecl illuminationTableOption() {
  return OptionDecl("illumination_table")
      .help(
          "map the visible fraction of the light's diameter to illumination with Lawlor's Appendix A table for the "
          "light's profile (disk lights; identity for rect, polygon)");
}

// smoothies and kirsch: where a ribbon texel's fade is measured.
inline OptionDecl subTexelOption() {
  return OptionDecl("sub_texel")
      .help(
          "measure the fade's distance to the silhouette edge from the pixel's own point in the map (each ribbon texel "
          "names its edge), not from the texel's centre as the paper's per-texel buffer does: the fade then moves "
          "continuously with the light instead of in one-texel steps");
}

struct PlmOptions {
  LightMapOptions lightMap = kSoftLightMap;  //!< the light map g: size, fit and horizon
  DepthBias bias;                            //!< of the compares with g, c and b (shadow_map.h)
  float marginTexels = 2.0f;                 //!< added to every ribbon's half-width
  bool illuminationTable = true;             //!< V = f(l_g) through Appendix A's table (else V = l_g)
  bool fitLowerLimit = true;                 //!< b fitted to sampled visibility (else b is left unset)

  static void describe(OptionFields<PlmOptions>& f) {
    f.nest(&PlmOptions::lightMap);
    f.nest(&PlmOptions::bias);
    f.add(&PlmOptions::marginTexels, ribbonMarginOption());
    f.add(&PlmOptions::illuminationTable, illuminationTableOption());
    f.add(&PlmOptions::fitLowerLimit,
          OptionDecl("fit_lower_limit")
              .help("fit the geometry lower limit b to the visibility sampled along each ribbon texel's ray (16 rays "
                    "per receiver probed; our step 3, see plm.cpp); false leaves b unset, so receivers below deeper "
                    "geometry take the ribbon's penumbra and the umbra under stacked or folded occluders is lit: for "
                    "measuring what the fit costs and what it repairs"));
  }
};

struct SmoothiesOptions {
  LightMapOptions lightMap = kSoftLightMap;  //!< the light map: size, fit and horizon
  DepthBias bias;                            //!< of the hard compare and the smoothie compare (shadow_map.h)
  float marginTexels = 2.0f;                 //!< added to every smoothie's width
  bool illuminationTable = true;
  bool subTexel = true;  //!< the fade's distance from the pixel's point in the map (else the texel's centre)

  static void describe(OptionFields<SmoothiesOptions>& f) {
    f.nest(&SmoothiesOptions::lightMap);
    f.nest(&SmoothiesOptions::bias);
    f.add(&SmoothiesOptions::marginTexels, ribbonMarginOption());
    f.add(&SmoothiesOptions::illuminationTable, illuminationTableOption());
    f.add(&SmoothiesOptions::subTexel, subTexelOption());
  }
};

struct KirschOptions {
  LightMapOptions lightMap = kSoftLightMap;  //!< the light map: size, fit and horizon
  DepthBias bias;                            //!< of the hard compare (shadow_map.h)
  float marginTexels = 2.0f;                 //!< added to every ribbon's width
  bool illuminationTable = true;
  bool subTexel = true;  //!< the fade's distance from the pixel's point in the map (else the texel's centre)

  static void describe(OptionFields<KirschOptions>& f) {
    f.nest(&KirschOptions::lightMap);
    f.nest(&KirschOptions::bias);
    f.add(&KirschOptions::marginTexels, ribbonMarginOption());
    f.add(&KirschOptions::illuminationTable, illuminationTableOption());
    f.add(&KirschOptions::subTexel, subTexelOption());
  }
};

// The technique made from its options (the registry makes the same from parameters by name).
std::unique_ptr<ShadowTechnique> makeTechnique(const PlmOptions& options);        // plm
std::unique_ptr<ShadowTechnique> makeTechnique(const SmoothiesOptions& options);  // smoothies
std::unique_ptr<ShadowTechnique> makeTechnique(const KirschOptions& options);     // kirsch

}  // namespace penumbra
