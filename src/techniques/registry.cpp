// The registry: the one list of techniques. Adding a technique = its own file defining
// `TechniqueInfo <name>TechniqueInfo()` plus one line here.
#include "penumbra/registry.h"

#include <fmt/ranges.h>

#include "penumbra/error.h"

namespace penumbra {

TechniqueInfo referenceTechniqueInfo();
TechniqueInfo noneTechniqueInfo();
TechniqueInfo raytracedHardTechniqueInfo();
TechniqueInfo hardTechniqueInfo();
TechniqueInfo pcfTechniqueInfo();
TechniqueInfo pcssTechniqueInfo();
TechniqueInfo multisampleTechniqueInfo();
TechniqueInfo brabecTechniqueInfo();
TechniqueInfo plmTechniqueInfo();
TechniqueInfo smoothiesTechniqueInfo();
TechniqueInfo kirschTechniqueInfo();
TechniqueInfo heidrichTechniqueInfo();
TechniqueInfo parkerTechniqueInfo();
TechniqueInfo ssvTechniqueInfo();
TechniqueInfo wedgesTechniqueInfo();

const std::vector<TechniqueInfo>& techniqueRegistry() {
  static const std::vector<TechniqueInfo> registry = {
      referenceTechniqueInfo(),
      noneTechniqueInfo(),
      hardTechniqueInfo(),
      raytracedHardTechniqueInfo(),
      pcfTechniqueInfo(),
      pcssTechniqueInfo(),
      multisampleTechniqueInfo(),
      brabecTechniqueInfo(),
      plmTechniqueInfo(),
      smoothiesTechniqueInfo(),
      kirschTechniqueInfo(),
      heidrichTechniqueInfo(),
      parkerTechniqueInfo(),
      ssvTechniqueInfo(),
      wedgesTechniqueInfo(),
  };
  return registry;
}

bool TechniqueInfo::hasParam(const std::string& param) const {
  for (const ParamSpec& p : params)
    if (p.name == param) return true;
  return false;
}

const TechniqueInfo& findTechnique(const std::string& name) {
  std::vector<std::string> names;
  for (const TechniqueInfo& info : techniqueRegistry()) {
    if (info.name == name) return info;
    names.push_back(info.name);
  }
  fail("unknown technique '{}' (known: {}; `penumbra techniques` lists them with their parameters)", name,
       fmt::join(names, ", "));
}

std::unique_ptr<ShadowTechnique> createTechnique(const std::string& name, const ParamSet& given) {
  const TechniqueInfo& info = findTechnique(name);
  return info.create(resolveParams(info.name, info.params, given));
}

}  // namespace penumbra
