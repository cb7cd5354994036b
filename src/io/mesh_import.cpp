// Mesh files through assimp (OBJ, PLY, glTF/GLB, STL, ...): every triangle of every mesh in the
// file, node transforms applied (aiProcess_PreTransformVertices), merged into one Mesh in the file's
// own coordinates and units.
//
// Vertices are joined where position and normal agree (aiProcess_JoinIdenticalVertices, after
// dropping texture coordinates and colours, which penumbra does not use), so a file that shares
// vertices gives a watertight mesh; a file with hard per-face normals keeps its split vertices.
// Vertex normals are kept only when every mesh in the file has them; otherwise the mesh is flat
// (face normals), because a mix would interpolate normals that exist with ones that do not.
// Points and lines are not surfaces and are not imported; a file without any triangle is an error.
// assimp's logger stays the default null logger, so nothing is printed.
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>
#include <vector>

#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/Importer.hpp>

#include "penumbra/error.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

// assimp 5.2.5 (Debian 12) loops forever on a PLY file whose header never reaches its `end_header`
// line (a truncated file does that), so such a file is refused before assimp sees it. assimp picks
// the PLY reader by the extension or by a leading "ply"; both are checked here.
void checkPlyHeader(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string line;
  if (!std::getline(in, line)) return;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  // assimp's content check takes any file that opens with "ply" (a fuzz finding: "ply t..." named
  // .obj went to the PLY reader, which then read past its buffer), so the prefix decides here too.
  if (line.rfind("ply", 0) != 0 && extension != ".ply") return;
  // The PLY header is text lines up to "end_header"; real headers are well under this many lines.
  constexpr int kMaxHeaderLines = 100000;
  for (int i = 0; i < kMaxHeaderLines && std::getline(in, line); ++i) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line == "end_header") return;
  }
  fail("{}: the PLY header has no 'end_header' line; expected a complete PLY file (is it truncated?)", path);
}

// assimp 5.2.5 reserves memory for the element counts a PLY or OFF header declares before reading
// any element, so a header that declares billions (assimp-testmodels' invalid/OutOfMemory.off) takes
// all the machine's memory. Every element takes at least one byte of the file, so a count larger
// than the file is refused before assimp sees it.
void checkDeclaredCounts(const std::string& path, uintmax_t fileSize) {
  std::ifstream in(path, std::ios::binary);
  std::string first;
  if (!(in >> first)) return;
  std::string extension = std::filesystem::path(path).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const auto tooMany = [&](const std::string& what, const std::string& count) {
    // assimp reads a count with strtoul, so a sign or an overflow becomes a huge allocation too.
    if (count.empty() || count.find_first_not_of("0123456789") != std::string::npos)
      fail("{}: the header's count of {} is '{}'; expected a non-negative integer", path, what, count);
    if (count.size() > 19 || std::stoull(count) > fileSize)
      fail("{}: the header declares {} {}, more than the file's {} bytes could hold; expected a complete file", path,
           count, what, fileSize);
  };
  if (first == "ply" || extension == ".ply") {
    std::string line;
    std::getline(in, line);
    for (int i = 0; i < 100000 && std::getline(in, line); ++i) {
      std::istringstream words(line);
      std::string keyword, name, count;
      words >> keyword;
      if (keyword == "end_header") return;
      if (keyword == "element" && words >> name >> count) tooMany(name + " elements", count);
    }
  } else if (extension == ".off" || (first.size() >= 3 && first.compare(first.size() - 3, 3, "OFF") == 0)) {
    // "[C][N][4][n]OFF" then the vertex and face counts (on the same line or the next), '#' comments between.
    std::string token;
    std::vector<std::string> counts;
    if (first.find("OFF") == std::string::npos) counts.push_back(first);
    while (counts.size() < 2 && in >> token) {
      if (token[0] == '#') {
        std::getline(in, token);
        continue;
      }
      counts.push_back(token);
    }
    if (counts.size() == 2) {
      tooMany("vertices", counts[0]);
      tooMany("faces", counts[1]);
      // assimp 5.2.5 aborts the process on an OFF file with fewer vertex and face lines than its
      // header declares (found by the mesh-file fuzz target), so a truncated file is refused here.
      if (counts[0].find_first_not_of("0123456789") == std::string::npos &&
          counts[1].find_first_not_of("0123456789") == std::string::npos && counts[0].size() < 19 &&
          counts[1].size() < 19) {
        const unsigned long long vertices = std::stoull(counts[0]);
        const unsigned long long declared = vertices + std::stoull(counts[1]);
        std::string line;
        std::getline(in, line);  // the rest of the counts line
        unsigned long long lines = 0;
        while (lines < declared && std::getline(in, line)) {
          const size_t start = line.find_first_not_of(" \t\r");
          if (start == std::string::npos || line[start] == '#') continue;
          // A face line opens with its vertex count; assimp 5.2.5 reads out of bounds on a face of
          // none (found by the mesh-file fuzz target), and only polygons give triangles.
          if (lines >= vertices) {
            std::istringstream words(line);
            long long corners = 0;
            if (!(words >> corners) || corners < 3)
              fail("{}: face {} starts with '{}'; expected its vertex count, 3 or more", path, lines - vertices,
                   line.substr(start, line.find_first_of(" \t\r", start) - start));
          }
          ++lines;
        }
        if (lines < declared)
          fail("{}: the header declares {} vertices and {} faces but only {} lines follow; expected a complete file",
               path, counts[0], counts[1], lines);
      }
    }
  }
}

}  // namespace

Mesh importMesh(const std::string& path, uint64_t maxBytes) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) {
    // The real-mesh scenes use the models Debian's assimp-testmodels installs: say which package is missing.
    if (path.rfind(kAssimpTestModels, 0) == 0)
      fail(
          "{}: mesh file not found; it is one of the models of Debian's assimp-testmodels package: install it "
          "(apt-get install assimp-testmodels, or scripts/install-deps)",
          path);
    fail("{}: mesh file not found (check the path; relative paths start at the scene file's folder)", path);
  }
  if (!std::filesystem::is_regular_file(status))
    fail("{}: expected a mesh file, found a directory or special file", path);
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) fail("{}: cannot read the mesh file ({})", path, ec.message());
  if (size == 0) fail("{}: the mesh file is empty; expected triangles", path);
  if (size > maxBytes)
    fail(
        "{}: the mesh file is {} bytes, over the limit of {} bytes ({:.4g} MiB); raise it with --max-mesh-size MiB if "
        "the "
        "file is meant to be this large",
        path, size, maxBytes, static_cast<double>(maxBytes) / (1024.0 * 1024.0));
  checkPlyHeader(path);
  checkDeclaredCounts(path, size);

  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS,
                              aiComponent_TEXCOORDS | aiComponent_COLORS | aiComponent_TANGENTS_AND_BITANGENTS |
                                  aiComponent_BONEWEIGHTS | aiComponent_ANIMATIONS | aiComponent_TEXTURES |
                                  aiComponent_LIGHTS | aiComponent_CAMERAS | aiComponent_MATERIALS);
  const aiScene* scene = importer.ReadFile(path, aiProcess_RemoveComponent);
  if (scene == nullptr) fail("{}: cannot import the mesh file: {}", path, importer.GetErrorString());
  if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)
    fail("{}: the mesh file is incomplete (assimp could not read all of it)", path);
  // Faces are checked before any post-processing step reads them: assimp's triangulation aborts the
  // process (an assertion) on a face without indices, and later steps index vertices by them.
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* in = scene->mMeshes[m];
    for (unsigned f = 0; f < in->mNumFaces; ++f) {
      if (in->mFaces[f].mNumIndices == 0)
        fail("{}: face {} (of mesh {}) has no vertices; expected a polygon with 3 or more", path, f, m);
      for (unsigned k = 0; k < in->mFaces[f].mNumIndices; ++k)
        if (in->mFaces[f].mIndices[k] >= in->mNumVertices)
          fail("{}: face {} (of mesh {}) uses vertex {}, but the mesh has {} vertices; expected indices below {}", path,
               f, m, in->mFaces[f].mIndices[k], in->mNumVertices, in->mNumVertices);
    }
  }
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_PreTransformVertices);
  if (scene == nullptr) fail("{}: cannot import the mesh file: {}", path, importer.GetErrorString());
  // Non-finite positions are refused before vertices are joined: JoinIdenticalVertices compares with
  // a tolerance that a NaN passes, and silently replaces a NaN vertex by a finite one.
  for (unsigned m = 0, index = 0; m < scene->mNumMeshes; ++m)
    for (unsigned v = 0; v < scene->mMeshes[m]->mNumVertices; ++v, ++index) {
      const aiVector3D& p = scene->mMeshes[m]->mVertices[v];
      if (!isFinite(Vec3(p.x, p.y, p.z)))
        fail("{}: vertex {} (of mesh {}) is not finite ({}, {}, {}); expected finite coordinates", path, index, m, p.x,
             p.y, p.z);
    }
  scene = importer.ApplyPostProcessing(aiProcess_JoinIdenticalVertices);
  if (scene == nullptr) fail("{}: cannot import the mesh file: {}", path, importer.GetErrorString());

  bool allHaveNormals = scene->mNumMeshes > 0;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) allHaveNormals = allHaveNormals && scene->mMeshes[m]->HasNormals();

  Mesh mesh;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh* in = scene->mMeshes[m];
    const auto base = static_cast<uint32_t>(mesh.positions.size());
    bool anyTriangle = false;
    for (unsigned f = 0; f < in->mNumFaces; ++f) {
      const aiFace& face = in->mFaces[f];
      if (face.mNumIndices != 3) continue;  // points and lines
      // A triangle that repeats a vertex (joined vertices of a sliver, or written so) covers no area
      // and blocks no light; dropping it keeps every imported mesh valid as an inline mesh too.
      if (face.mIndices[0] == face.mIndices[1] || face.mIndices[1] == face.mIndices[2] ||
          face.mIndices[0] == face.mIndices[2])
        continue;
      mesh.triangles.emplace_back(base + face.mIndices[0], base + face.mIndices[1], base + face.mIndices[2]);
      anyTriangle = true;
    }
    if (!anyTriangle) continue;  // a point cloud or line set in the file: keep no stray vertices
    for (unsigned v = 0; v < in->mNumVertices; ++v) {
      const aiVector3D& p = in->mVertices[v];
      const Vec3 position(p.x, p.y, p.z);
      if (!isFinite(position))
        fail("{}: vertex {} (of mesh {}) is not finite ({}, {}, {}); expected finite coordinates", path,
             mesh.positions.size(), m, p.x, p.y, p.z);
      mesh.positions.push_back(position);
      if (allHaveNormals) {
        const aiVector3D& n = in->mNormals[v];
        Vec3 normal(n.x, n.y, n.z);
        const float len = glm::length(normal);
        // A zero or non-finite normal (assimp writes NaN for unreferenced vertices) gets no shading
        // direction; mark the whole mesh flat rather than invent one.
        if (!(len > 0.0f) || !std::isfinite(len))
          allHaveNormals = false;
        else
          mesh.normals.push_back(normal / len);
      }
    }
  }
  if (!allHaveNormals) mesh.normals.clear();
  if (mesh.triangles.empty()) fail("{}: the mesh file holds no triangles; expected a surface mesh", path);
  return mesh;
}

}  // namespace penumbra
