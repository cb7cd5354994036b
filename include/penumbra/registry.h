// The registry: the one place that lists the techniques, their factories and parameter schemas.
// The CLI, scene files and reports read names, parameters, defaults and help from here.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/params.h"
#include "penumbra/technique.h"

namespace penumbra {

struct TechniqueInfo {
  std::string name;     //!< "reference", "hard", ...
  std::string summary;  //!< one line
  std::string source;   //!< paper or "baseline"
  std::string lights;   //!< the light shapes it takes and how it treats them, a concave polygon included
  std::vector<ParamSpec> params;
  std::function<std::unique_ptr<ShadowTechnique>(const Params&)> create;

  bool hasParam(const std::string& param) const;
};

// All registered techniques, in the order of DESIGN.md's table.
const std::vector<TechniqueInfo>& techniqueRegistry();

// The technique called `name`; throws Error listing the known names otherwise.
const TechniqueInfo& findTechnique(const std::string& name);

// Validates `given` against the technique's schema and builds it.
std::unique_ptr<ShadowTechnique> createTechnique(const std::string& name, const ParamSet& given = {});

}  // namespace penumbra
