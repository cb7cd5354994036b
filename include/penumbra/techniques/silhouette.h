// The geometric family's typed options and factories (docs/techniques.md): ssv (soft shadow volumes,
// Rouf 2007) and wedges (penumbra wedges, Assarsson & Akenine-Möller 2003). A concave light runs as its
// convex parts, V combined by area. See shadow_map.h of this folder for how options and factories are
// used.
#pragma once

#include <memory>

#include "penumbra/options.h"
#include "penumbra/technique.h"

namespace penumbra {

// How ssv integrates the visible fraction of the light (its parameter `integration`).
enum class SsvIntegration { Slicing, Fixed8, Fixed16 };

struct SsvOptions {
  SsvIntegration integration = SsvIntegration::Slicing;
  float mergeTolerance = 0.01f;     //!< slicing: cuts closer than this (fraction of the light's side) merge
  int grid = 64;                    //!< cells per side of the light-space binning grid
  bool areaEdgeVisibility = false;  //!< per edge, the exact light area past its line instead of the linear ramp

  static void describe(OptionFields<SsvOptions>& f) {
    f.add(&SsvOptions::integration,
          OptionDecl("integration")
              .help("visible fraction from the visibility curves: slicing (variable "
                    "quantization, Section 3.2.4.4) or fixed 8x8 / 16x16 sampling (Fig. 4-8)"),
          {{"slicing", SsvIntegration::Slicing}, {"8x8", SsvIntegration::Fixed8}, {"16x16", SsvIntegration::Fixed16}});
    f.add(&SsvOptions::mergeTolerance,
          OptionDecl("merge_tolerance")
              .range(0, 0.25)
              .unit("fraction of the light's side")
              .help("slicing: two cut coordinates closer than this count as one (0.01 in the thesis, Section 4.2.6)"));
    f.add(&SsvOptions::grid,
          OptionDecl("grid")
              .range(1, 1024)
              .unit("cells per side")
              .help("resolution of the light-space (direction from the light's centre) grid that bins the "
                    "edge shadows"));
    f.add(&SsvOptions::areaEdgeVisibility,
          OptionDecl("edge_visibility")
              .help("visible fraction past one edge shadow: linear between its front and "
                    "back planes (the thesis, Section 3.3) or the exact area of the light "
                    "past the edge's line"),
          {{"linear", false}, {"area", true}});
  }
};

struct WedgesOptions {
  int grid = 64;  //!< cells per side of the light-space binning grid

  static void describe(OptionFields<WedgesOptions>& f) {
    f.add(&WedgesOptions::grid,
          OptionDecl("grid")
              .range(1, 1024)
              .unit("cells per side")
              .help("resolution of the light-space (direction from the light's centre) grid that bins "
                    "the silhouette rings"));
  }
};

// The technique made from its options (the registry makes the same from parameters by name).
std::unique_ptr<ShadowTechnique> makeTechnique(const SsvOptions& options);     // ssv
std::unique_ptr<ShadowTechnique> makeTechnique(const WedgesOptions& options);  // wedges

}  // namespace penumbra
