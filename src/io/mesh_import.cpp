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
#include <cmath>
#include <filesystem>
#include <system_error>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "penumbra/error.h"
#include "penumbra/scene_io.h"

namespace penumbra {

Mesh importMesh(const std::string& path) {
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) fail("{}: mesh file not found (check the path; relative paths start at the scene file's folder)", path);
  if (!std::filesystem::is_regular_file(status)) fail("{}: expected a mesh file, found a directory or special file", path);
  const auto size = std::filesystem::file_size(path, ec);
  if (ec) fail("{}: cannot read the mesh file ({})", path, ec.message());
  if (size == 0) fail("{}: the mesh file is empty; expected triangles", path);

  Assimp::Importer importer;
  importer.SetPropertyInteger(AI_CONFIG_PP_RVC_FLAGS, aiComponent_TEXCOORDS | aiComponent_COLORS |
                                                          aiComponent_TANGENTS_AND_BITANGENTS | aiComponent_BONEWEIGHTS |
                                                          aiComponent_ANIMATIONS | aiComponent_TEXTURES | aiComponent_LIGHTS |
                                                          aiComponent_CAMERAS | aiComponent_MATERIALS);
  const aiScene* scene = importer.ReadFile(path, aiProcess_RemoveComponent | aiProcess_Triangulate |
                                                     aiProcess_JoinIdenticalVertices | aiProcess_PreTransformVertices);
  if (scene == nullptr) fail("{}: cannot import the mesh file: {}", path, importer.GetErrorString());
  if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) fail("{}: the mesh file is incomplete (assimp could not read all of it)", path);

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
        if (!(len > 0.0f) || !std::isfinite(len)) allHaveNormals = false;
        else mesh.normals.push_back(normal / len);
      }
    }
  }
  if (!allHaveNormals) mesh.normals.clear();
  if (mesh.triangles.empty()) fail("{}: the mesh file holds no triangles; expected a surface mesh", path);
  return mesh;
}

}  // namespace penumbra
