// Scene files (docs/scene-format.md) and the built-in scenes (scenes/*.json, compiled in).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "penumbra/scene.h"

namespace penumbra {

struct BuiltinScene {
  std::string name;
  std::string description;  //!< one line, from the scene's "description"
};

std::vector<BuiltinScene> builtinScenes();

// The largest mesh file imported unless the caller raises it: 1 GiB. Importing takes several times a
// file's size in memory (assimp's own structures, then ours), and a file this large is more likely a
// mistake than a model; a larger one is refused before a byte of it is read.
inline constexpr uint64_t kDefaultMaxMeshBytes = uint64_t{1} << 30;

struct SceneLoadOptions {
  uint64_t maxMeshBytes = kDefaultMaxMeshBytes;  //!< mesh files above this size are refused, bytes
};

// A built-in scene name or a path to a JSON scene file. Throws Error naming the file and field.
Scene loadScene(const std::string& nameOrPath, const SceneLoadOptions& options = {});
// Parses scene JSON text; `source` names it in messages, `baseDir` resolves relative mesh paths.
Scene parseScene(const std::string& jsonText, const std::string& source, const std::string& baseDir = ".",
                 const SceneLoadOptions& options = {});
// Writes a scene as JSON that parseScene reads back to the same scene (meshes inline).
std::string sceneToJson(const Scene& scene);

// Imports a mesh file through assimp (OBJ, PLY, glTF/GLB, STL, ...), all meshes merged, in the
// file's own coordinates. Throws Error naming the file on failure, when it holds no triangles, or
// when it is larger than maxBytes (checked before it is read).
Mesh importMesh(const std::string& path, uint64_t maxBytes = kDefaultMaxMeshBytes);

// Where Debian's assimp-testmodels package installs its models, which the real-mesh built-in scenes
// and the test corpus (tests/corpus/) use; a missing file there is reported as a missing package.
inline constexpr const char* kAssimpTestModels = "/usr/share/assimp/models/";

}  // namespace penumbra
