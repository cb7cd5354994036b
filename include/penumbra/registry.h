// The registry: the one place that lists the techniques, their factories and parameter schemas.
// The CLI, scene files and reports read names, parameters, defaults and help from here.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "penumbra/options.h"
#include "penumbra/params.h"
#include "penumbra/technique.h"

namespace penumbra {

// What one run of a technique will take, estimated from its parameters and the image size before any
// work, so that a caller can refuse what cannot fit in memory and warn about what will take long
// (the CLI does both, with --force to go on). Measured peaks, not bounds: within about 10%.
struct ResourceEstimate {
  double bytes = 0.0;   //!< peak memory of the technique's own buffers beyond the G-buffer, bytes
  double rays = 0.0;    //!< shadow rays traced
  double texels = 0.0;  //!< light-map texels rendered, each map counted once
  std::string drivers;  //!< the parameters that set it, as the user writes them: "map_size=8192, samples=1024"
};

struct TechniqueInfo {
  std::string name;            //!< "reference", "hard", ...
  std::string summary;         //!< one line
  std::string source;          //!< paper or "baseline"
  std::string lights;          //!< the light shapes it takes and how it treats them, a concave polygon included
  bool tracesRays = false;     //!< its prepare uses the scene's shared Embree scene (Scene::caches)
  bool usesMeshEdges = false;  //!< its prepare uses the meshes' shared edge adjacency (Scene::caches)
  std::vector<ParamSpec> params;
  std::function<std::unique_ptr<ShadowTechnique>(const Params&)> create;
  std::function<ResourceEstimate(const Params&, int width, int height)>
      estimate;  //!< set by the registry for every technique

  bool hasParam(const std::string& param) const;

  // Sets params and create from one options struct (options.h): params is its schema, create
  // parses the resolved Params into it and hands it to `make`, which builds the technique.
  template <class Options, class Make>
  void setOptions(Make make) {
    params = paramSchema<Options>();
    create = [make](const Params& resolved) -> std::unique_ptr<ShadowTechnique> {
      return make(optionsFromParams<Options>(resolved));
    };
  }
};

// All registered techniques, in the order of docs/architecture.md's table.
const std::vector<TechniqueInfo>& techniqueRegistry();

// The technique called `name`; throws Error listing the known names otherwise.
const TechniqueInfo& findTechnique(const std::string& name);

// Validates `given` against the technique's schema and builds it.
std::unique_ptr<ShadowTechnique> createTechnique(const std::string& name, const ParamSet& given = {});

}  // namespace penumbra
