// Tests of mesh import through assimp (src/io/mesh_import.cpp). The test writes the same closed
// box (penumbra's own makeBox) as OBJ, ASCII PLY, glTF with an embedded buffer, and binary GLB, and
// checks every import gives the same triangles with the same winding; glTF node transforms are
// applied; bad files (NaN vertex, empty, no triangles, garbage) are rejected naming the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "penumbra/error.h"
#include "penumbra/primitives.h"
#include "penumbra/scene_io.h"

namespace penumbra {
namespace {

using json = nlohmann::json;

class TempDir {
 public:
  TempDir() {
    path_ = std::filesystem::temp_directory_path() /
            ("penumbra_mesh_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::create_directories(path_);
  }
  ~TempDir() { std::filesystem::remove_all(path_); }
  std::string file(const std::string& name, const std::string& bytes) const {
    const std::string p = (path_ / name).string();
    std::ofstream(p, std::ios::binary) << bytes;
    return p;
  }

 private:
  std::filesystem::path path_;
};

// A triangle as its three corner positions, rotated so the smallest corner comes first: equal for
// equal triangles with equal winding, whatever the vertex order in the file.
using Corners = std::array<std::array<float, 3>, 3>;
std::multiset<Corners> triangleSet(const Mesh& m, const Vec3& offset = Vec3(0.0f)) {
  std::multiset<Corners> set;
  for (const glm::uvec3& t : m.triangles) {
    Corners c;
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = m.positions[t[k]] - offset;
      c[k] = {p.x, p.y, p.z};
    }
    const auto first = std::min_element(c.begin(), c.end()) - c.begin();
    std::rotate(c.begin(), c.begin() + first, c.end());
    set.insert(c);
  }
  return set;
}

// Closed by index: every directed edge once, and its reverse once.
bool closedByIndex(const Mesh& m) {
  std::multiset<std::pair<uint32_t, uint32_t>> edges;
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) edges.insert({t[k], t[(k + 1) % 3]});
  for (const auto& e : edges)
    if (edges.count(e) != 1 || edges.count({e.second, e.first}) != 1) return false;
  return true;
}

// A box with edge lengths that are exact in decimal and in float, so text formats round-trip.
Mesh testBox() { return makeBox(Vec3(1.0f, 2.0f, 0.5f)); }

std::string toObj(const Mesh& m) {
  std::ostringstream s;
  s << "# box\n";
  for (const Vec3& p : m.positions) s << "v " << p.x << " " << p.y << " " << p.z << "\n";
  for (const glm::uvec3& t : m.triangles) s << "f " << t.x + 1 << " " << t.y + 1 << " " << t.z + 1 << "\n";
  return s.str();
}

std::string toPly(const Mesh& m) {
  std::ostringstream s;
  s << "ply\nformat ascii 1.0\nelement vertex " << m.positions.size()
    << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << m.triangles.size()
    << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (const Vec3& p : m.positions) s << p.x << " " << p.y << " " << p.z << "\n";
  for (const glm::uvec3& t : m.triangles) s << "3 " << t.x << " " << t.y << " " << t.z << "\n";
  return s.str();
}

std::string base64(const std::string& bytes) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t n = static_cast<uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) n |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) n |= static_cast<uint8_t>(bytes[i + 2]);
    out += alphabet[(n >> 18) & 63];
    out += alphabet[(n >> 12) & 63];
    out += i + 1 < bytes.size() ? alphabet[(n >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? alphabet[n & 63] : '=';
  }
  return out;
}

// The glTF buffer (float32 positions, then uint16 indices) and the JSON describing it, with one
// node carrying `translation`.
std::pair<json, std::string> gltfParts(const Mesh& m, const Vec3& translation) {
  std::string buffer;
  Vec3 lower(kInfinity), upper(-kInfinity);
  for (const Vec3& p : m.positions) {
    buffer.append(reinterpret_cast<const char*>(&p), sizeof(float) * 3);
    lower = glm::min(lower, p);
    upper = glm::max(upper, p);
  }
  const size_t positionBytes = buffer.size();
  for (const glm::uvec3& t : m.triangles)
    for (int k = 0; k < 3; ++k) {
      const uint16_t i = static_cast<uint16_t>(t[k]);
      buffer.append(reinterpret_cast<const char*>(&i), sizeof(i));
    }
  while (buffer.size() % 4) buffer.push_back('\0');
  json j = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", {{{"mesh", 0}, {"translation", {translation.x, translation.y, translation.z}}}}},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}, {"mode", 4}}}}}}},
      {"buffers", {{{"byteLength", buffer.size()}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", positionBytes}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", positionBytes}, {"byteLength", m.triangles.size() * 6}, {"target", 34963}}}},
      {"accessors",
       {{{"bufferView", 0},
         {"componentType", 5126},
         {"count", m.positions.size()},
         {"type", "VEC3"},
         {"min", {lower.x, lower.y, lower.z}},
         {"max", {upper.x, upper.y, upper.z}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", m.triangles.size() * 3}, {"type", "SCALAR"}}}},
  };
  return {j, buffer};
}

std::string toGltf(const Mesh& m, const Vec3& translation) {
  auto [j, buffer] = gltfParts(m, translation);
  j["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64(buffer);
  return j.dump();
}

std::string toGlb(const Mesh& m, const Vec3& translation) {
  auto [j, buffer] = gltfParts(m, translation);
  std::string text = j.dump();
  while (text.size() % 4) text.push_back(' ');
  const auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
  std::string glb = u32(0x46546C67) + u32(2) + u32(static_cast<uint32_t>(12 + 8 + text.size() + 8 + buffer.size()));
  glb += u32(static_cast<uint32_t>(text.size())) + u32(0x4E4F534A) + text;
  glb += u32(static_cast<uint32_t>(buffer.size())) + u32(0x004E4942) + buffer;
  return glb;
}

std::string errorOf(const std::string& path) {
  try {
    importMesh(path);
  } catch (const Error& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected an error importing " << path;
  return "";
}

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE((haystack).find(needle), std::string::npos) << "message: " << (haystack)

TEST(MeshImport, ObjPlyGltfAndGlbGiveTheSameTriangles) {
  TempDir dir;
  const Mesh box = testBox();
  const auto expected = triangleSet(box);
  const Vec3 translation(1.0f, 2.0f, 3.0f);
  const std::vector<std::pair<std::string, Vec3>> files = {
      {dir.file("box.obj", toObj(box)), Vec3(0.0f)},
      {dir.file("box.ply", toPly(box)), Vec3(0.0f)},
      {dir.file("box.gltf", toGltf(box, translation)), translation},
      {dir.file("box.glb", toGlb(box, translation)), translation},
  };
  for (const auto& [path, offset] : files) {
    SCOPED_TRACE(path);
    const Mesh m = importMesh(path);
    EXPECT_EQ(m.triangleCount(), 12u);
    EXPECT_EQ(m.positions.size(), 8u);  // shared vertices stay shared
    EXPECT_TRUE(closedByIndex(m));
    EXPECT_TRUE(m.normals.empty());  // the files hold no normals: flat
    EXPECT_EQ(triangleSet(m, offset), expected);
  }
}

TEST(MeshImport, QuadsAreTriangulatedAndObjectsMerged) {
  TempDir dir;
  const std::string path = dir.file("two.obj",
                                    "o first\nv 0 0 0\nv 1 0 0\nv 1 0 -1\nv 0 0 -1\nf 1 2 3 4\n"
                                    "o second\nv 0 1 0\nv 1 1 0\nv 0 1 -1\nf 5 6 7\n");
  const Mesh m = importMesh(path);
  EXPECT_EQ(m.triangleCount(), 3u);
  double area = 0.0;
  for (size_t i = 0; i < m.triangleCount(); ++i) {
    const glm::uvec3& t = m.triangles[i];
    area += 0.5 * glm::length(glm::cross(m.positions[t.y] - m.positions[t.x], m.positions[t.z] - m.positions[t.x]));
    EXPECT_EQ(m.faceNormal(i), Vec3(0, 1, 0));  // winding kept
  }
  EXPECT_NEAR(area, 1.5, 1e-6);
}

TEST(MeshImport, TrianglesThatRepeatAVertexAreDropped) {
  TempDir dir;
  // Two faces repeat a vertex, directly or once identical vertices are joined (5 and 1 coincide):
  // they cover no area; the one real triangle stays, and the mesh reads back as an inline mesh.
  const std::string path =
      dir.file("d.obj", "v 0 0 0\nv 1 0 0\nv 0 0 -1\nv 2 0 0\nv 0 0 0\nf 1 2 3\nf 1 1 4\nf 1 5 2\n");
  const Mesh m = importMesh(path);
  ASSERT_EQ(m.triangleCount(), 1u);
  const glm::uvec3& t = m.triangles[0];
  EXPECT_TRUE(t.x != t.y && t.y != t.z && t.x != t.z);
}

TEST(MeshImport, NormalsFromTheFileAreKept) {
  TempDir dir;
  const std::string path = dir.file("n.obj", "v 0 0 0\nv 1 0 0\nv 0 0 -1\nvn 0 2 0\nf 1//1 2//1 3//1\n");
  const Mesh m = importMesh(path);
  ASSERT_EQ(m.normals.size(), m.positions.size());
  for (const Vec3& n : m.normals) EXPECT_EQ(n, Vec3(0, 1, 0));  // normalized
}

TEST(MeshImport, NanVertexIsRejectedWithItsIndex) {
  TempDir dir;
  const std::string path = dir.file("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan -1\nf 1 2 3\n");
  const std::string m = errorOf(path);
  EXPECT_CONTAINS(m, path);
  EXPECT_CONTAINS(m, "vertex 2");
  EXPECT_CONTAINS(m, "finite");
}

TEST(MeshImport, InfiniteVertexInPlyIsRejected) {
  TempDir dir;
  Mesh box = testBox();
  box.positions[5].x = kInfinity;
  const std::string path = dir.file("inf.ply", toPly(box));
  const std::string m = errorOf(path);
  EXPECT_CONTAINS(m, path);
  EXPECT_CONTAINS(m, "not finite");
}

TEST(MeshImport, BadFilesAreNamed) {
  TempDir dir;
  const std::string empty = dir.file("empty.obj", "");
  EXPECT_CONTAINS(errorOf(empty), empty + ": the mesh file is empty");
  const std::string lines = dir.file("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n");
  const std::string linesMessage = errorOf(lines);
  EXPECT_CONTAINS(linesMessage, lines);
  EXPECT_CONTAINS(linesMessage, "triangles");
  const std::string garbage = dir.file("garbage.ply", "this is not a ply file\n");
  EXPECT_CONTAINS(errorOf(garbage), garbage);
  const std::string missing = dir.file("x.txt", "x") + ".missing.obj";
  EXPECT_CONTAINS(errorOf(missing), missing + ": mesh file not found");
}

}  // namespace
}  // namespace penumbra
