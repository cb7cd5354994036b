// parker's typed options and factory (Parker, Shirley & Smits 1998; docs/techniques.md). See
// shadow_map.h of this folder for how options and factories are used.
#pragma once

#include <memory>
#include <optional>

#include "penumbra/options.h"
#include "penumbra/technique.h"

namespace penumbra {

enum class OuterFalloff { Bernstein, Sinusoid };  //!< s = 3 tau^2 - 2 tau^3, or (1 + sin(pi tau - pi/2)) / 2
enum class OuterCombine { Min, Product, Sum };    //!< how several grazed objects' attenuations combine

struct ParkerOptions {
  OuterFalloff falloff = OuterFalloff::Bernstein;
  OuterCombine combine = OuterCombine::Min;
  bool analyticSpheres = true;
  std::optional<float> lightDiameter;  //!< world units (directional: per unit distance); nullopt = derived

  static void describe(OptionFields<ParkerOptions>& f) {
    f.add(&ParkerOptions::falloff,
          OptionDecl("falloff").help("attenuation across the outer object: bernstein s = 3 tau^2 - 2 tau^3 (the "
                                     "paper's), or the exact sinusoid (1 + sin(pi tau - pi/2)) / 2 of a straight edge "
                                     "under a spherical light"),
          {{"bernstein", OuterFalloff::Bernstein}, {"sinusoid", OuterFalloff::Sinusoid}});
    f.add(&ParkerOptions::combine,
          OptionDecl("combine").help("how the attenuations of several grazed objects combine: min (the paper's "
                                     "thresholding, never darker than it should be), product s1 s2, or sum 1 - ((1 - "
                                     "s1) + (1 - s2)) (at least 0)"),
          {{"min", OuterCombine::Min}, {"product", OuterCombine::Product}, {"sum", OuterCombine::Sum}});
    f.add(&ParkerOptions::analyticSpheres,
          OptionDecl("analytic_spheres")
              .help("objects made from a sphere primitive are the true sphere (inner radius "
                    "R, outer R + b) instead of their tessellated mesh"));
    f.add(&ParkerOptions::lightDiameter,
          OptionDecl("light_diameter")
              .range(1e-6, 1e6)
              .unit("world units (directional: per unit distance)")
              .help("D of b = D t0 / |l - o|; auto: the light's bounding diameter (sphere: 2 radius; directional: 2 "
                    "tan(angular_diameter / 2))"));
  }
};

// The technique made from its options (the registry makes the same from parameters by name).
std::unique_ptr<ShadowTechnique> makeTechnique(const ParkerOptions& options);  // parker

}  // namespace penumbra
