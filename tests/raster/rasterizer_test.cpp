// Tests of the software rasterizer (src/raster/rasterizer.cpp) against exact, independent answers:
// the top-left fill rule on edges through pixel centres (counted per pixel, one triangle per call,
// so a double hit cannot hide behind the depth test), watertight meshes and fans, perspective-correct
// interpolation against the analytic ray-plane intersection, depth ordering against the analytic
// depth of interpenetrating triangles, near-plane clipping and the guard band against ray-triangle
// intersection in double precision, and bit-identical output for any thread count.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <random>

#include <tbb/global_control.h>
#include <tbb/task_arena.h>

#include "penumbra/error.h"
#include "raster/rasterizer.h"

namespace penumbra::raster {
namespace {

// Triangles with their own vectors, viewed through a RasterInput.
struct Mesh2 {
  int width = 0, height = 0;
  std::vector<Vec4> clip;
  std::vector<glm::uvec3> triangles;
  std::vector<int32_t> payloads;
  int attributeCount = 0;
  std::vector<float> attributes;

  RasterInput input() const {
    RasterInput in;
    in.width = width;
    in.height = height;
    in.clipPositions = clip;
    in.triangles = triangles;
    in.payloads = payloads;
    in.attributeCount = attributeCount;
    in.attributes = attributes;
    return in;
  }
  // A vertex given in raster space (pixels, y down) at NDC depth z, w = 1 (orthographic).
  uint32_t addRasterVertex(double x, double y, float z = 0.0f) {
    clip.emplace_back(static_cast<float>(2.0 * x / width - 1.0), static_cast<float>(1.0 - 2.0 * y / height), z, 1.0f);
    return static_cast<uint32_t>(clip.size() - 1);
  }
};

// Coverage count per pixel, rasterizing each triangle on its own.
Image<int> coverageCount(const Mesh2& mesh) {
  Image<int> count(mesh.width, mesh.height, 0);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    RasterInput in = mesh.input();
    in.triangles = std::span<const glm::uvec3>(mesh.triangles).subspan(t, 1);
    in.payloads = {};
    const RasterOutput out = rasterize(in);
    for (size_t i = 0; i < count.size(); ++i) count[i] += out.triangle[i] >= 0 ? 1 : 0;
  }
  return count;
}

TEST(Rasterizer, TopLeftRuleOnEdgesThroughPixelCentres) {
  // A 4 x 4 pixel square whose edges and diagonal pass through pixel centres: the left and top
  // edges own their centres, the right and bottom ones do not, and the diagonal's centres belong
  // to exactly one triangle — for either diagonal and either winding.
  for (int variant = 0; variant < 4; ++variant) {
    Mesh2 m;
    m.width = 12;
    m.height = 10;
    const uint32_t a = m.addRasterVertex(2.5, 1.5), b = m.addRasterVertex(6.5, 1.5);
    const uint32_t c = m.addRasterVertex(6.5, 5.5), d = m.addRasterVertex(2.5, 5.5);
    const bool otherDiagonal = variant & 1, flip = variant & 2;
    if (!otherDiagonal) {
      m.triangles = {{a, b, c}, flip ? glm::uvec3(a, d, c) : glm::uvec3(a, c, d)};
    } else {
      m.triangles = {{a, b, d}, flip ? glm::uvec3(b, d, c) : glm::uvec3(b, c, d)};
    }
    const Image<int> count = coverageCount(m);
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x) {
        const int expected = (x >= 2 && x <= 5 && y >= 1 && y <= 4) ? 1 : 0;
        EXPECT_EQ(count(x, y), expected) << "pixel " << x << "," << y << " variant " << variant;
      }
  }
}

TEST(Rasterizer, FanAroundAVertexOnAPixelCentreCoversEachPixelOnce) {
  Mesh2 m;
  m.width = 90;
  m.height = 80;
  const double cx = 40.5, cy = 37.5, radius = 30.0;
  const uint32_t centre = m.addRasterVertex(cx, cy);
  const int n = 13;
  std::vector<glm::dvec2> ring;
  for (int i = 0; i < n; ++i) {
    const double phi = 2.0 * M_PI * i / n;
    // Outer vertices on pixel centres, so many edges pass exactly through samples.
    ring.emplace_back(std::floor(cx + radius * std::cos(phi)) + 0.5, std::floor(cy + radius * std::sin(phi)) + 0.5);
    m.addRasterVertex(ring.back().x, ring.back().y);
  }
  for (int i = 0; i < n; ++i) m.triangles.emplace_back(centre, 1 + i, 1 + (i + 1) % n);
  const Image<int> count = coverageCount(m);
  int covered = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      ASSERT_LE(count(x, y), 1) << "pixel " << x << "," << y << " covered twice";
      // Signed distance of the pixel centre to the fan's outline (convex, ring in y-down CW order).
      const glm::dvec2 p(x + 0.5, y + 0.5);
      double inside = kInfinity;
      for (int i = 0; i < n; ++i) {
        const glm::dvec2 e = ring[(i + 1) % n] - ring[i];
        const glm::dvec2 q = p - ring[i];
        inside = std::min(inside, (e.x * q.y - e.y * q.x) / glm::length(e));
      }
      if (inside > 1e-9) {
        EXPECT_EQ(count(x, y), 1) << "gap at pixel " << x << "," << y;
      } else if (inside < -1e-9) {
        EXPECT_EQ(count(x, y), 0) << "pixel " << x << "," << y << " outside the fan";
      }
      covered += count(x, y);
    }
  EXPECT_EQ(count(40, 37), 1);  // the shared vertex's own pixel
  EXPECT_GT(covered, 2000);
}

TEST(Rasterizer, JitteredMeshBeyondTheImageCoversEveryPixelExactlyOnce) {
  // A grid mesh larger than the image, crossing several tiles, with jittered vertices (half of them
  // on pixel centres), random diagonals and random windings: every pixel exactly once.
  Mesh2 m;
  m.width = 150;
  m.height = 100;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-6.0, 6.0);
  const int nx = 9, ny = 7;
  const double sx = 180.0 / nx, sy = 130.0 / ny;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      double x = -15.0 + i * sx, y = -15.0 + j * sy;
      if (i > 0 && i < nx && j > 0 && j < ny) {
        x += jitter(rng);
        y += jitter(rng);
        if (rng() & 1) {
          x = std::floor(x) + 0.5;
          y = std::floor(y) + 0.5;
        }
      }
      m.addRasterVertex(x, y);
    }
  auto v = [&](int i, int j) { return static_cast<uint32_t>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const uint32_t a = v(i, j), b = v(i + 1, j), c = v(i + 1, j + 1), d = v(i, j + 1);
      glm::uvec3 t0(a, b, c), t1(a, c, d);
      if (rng() & 1) {
        t0 = glm::uvec3(a, b, d);
        t1 = glm::uvec3(b, c, d);
      }
      if (rng() & 1) {
        std::swap(t0.y, t0.z);
      }
      if (rng() & 1) {
        std::swap(t1.y, t1.z);
      }
      m.triangles.push_back(t0);
      m.triangles.push_back(t1);
    }
  const Image<int> count = coverageCount(m);
  int wrong = 0;
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) wrong += count(x, y) != 1;
  EXPECT_EQ(wrong, 0);
}

// A perspective camera at the origin looking down -z, with the G-buffer's reversed depth key.
struct Perspective {
  int width = 160, height = 120;
  float tanHalf = std::tan(radians(30.0f));
  float zNear = 0.1f;
  float aspect() const { return static_cast<float>(width) / height; }
  Vec4 clip(const Vec3& cs) const { return Vec4(cs.x / (tanHalf * aspect()), cs.y / tanHalf, -zNear, -cs.z); }
  glm::dvec3 rayDirection(int x, int y) const {
    const double ndcX = 2.0 * (x + 0.5) / width - 1.0, ndcY = 1.0 - 2.0 * (y + 0.5) / height;
    return {ndcX * tanHalf * aspect(), ndcY * tanHalf, -1.0};
  }
};

// Ray (from the origin) - triangle intersection in double (Moller-Trumbore): t and barycentrics.
struct Hit {
  bool hit = false;
  double t = 0.0, b1 = 0.0, b2 = 0.0;
  double edgeDistance = 0.0;  // min barycentric: how far inside the triangle
};
Hit intersect(const glm::dvec3& d, const glm::dvec3& p0, const glm::dvec3& p1, const glm::dvec3& p2) {
  Hit h;
  const glm::dvec3 e1 = p1 - p0, e2 = p2 - p0;
  const glm::dvec3 pv = glm::cross(d, e2);
  const double det = glm::dot(e1, pv);
  if (std::abs(det) < 1e-300) return h;
  const glm::dvec3 tv = -p0;
  h.b1 = glm::dot(tv, pv) / det;
  const glm::dvec3 qv = glm::cross(tv, e1);
  h.b2 = glm::dot(d, qv) / det;
  h.t = glm::dot(e2, qv) / det;
  h.edgeDistance = std::min({h.b1, h.b2, 1.0 - h.b1 - h.b2});
  h.hit = h.edgeDistance >= 0.0;
  return h;
}

Mesh2 perspectiveTriangle(const Perspective& cam, const std::array<Vec3, 3>& cs) {
  Mesh2 m;
  m.width = cam.width;
  m.height = cam.height;
  m.attributeCount = 3;
  for (const Vec3& p : cs) {
    m.clip.push_back(cam.clip(p));
    m.attributes.insert(m.attributes.end(), {p.x, p.y, p.z});
  }
  m.triangles = {{0, 1, 2}};
  m.payloads = {42};
  return m;
}

TEST(Rasterizer, PerspectiveCorrectInterpolationOnATiltedPlane) {
  const Perspective cam;
  // A plane strongly tilted in depth (view depth 1.5 to 12): affine interpolation is far off.
  const std::array<Vec3, 3> cs{Vec3(-1.2f, -0.9f, -1.5f), Vec3(6.0f, -2.0f, -12.0f), Vec3(-2.5f, 5.0f, -9.0f)};
  const Mesh2 m = perspectiveTriangle(cam, cs);
  const RasterOutput out = rasterize(m.input());
  const glm::dvec3 p0(cs[0]), p1(cs[1]), p2(cs[2]);
  double maxError = 0.0, maxAffineError = 0.0, maxDepthError = 0.0;
  int covered = 0, coverageMismatch = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const glm::dvec3 d = cam.rayDirection(x, y);
      const Hit h = intersect(d, p0, p1, p2);
      const bool rasterHit = out.triangle(x, y) == 0;
      if (std::abs(h.edgeDistance) > 1e-3) coverageMismatch += rasterHit != h.hit;
      if (!rasterHit) continue;
      ++covered;
      EXPECT_EQ(out.payload(x, y), 42);
      const glm::dvec3 expected = h.t * d;
      const glm::dvec3 got(out.attributes[0](x, y), out.attributes[1](x, y), out.attributes[2](x, y));
      maxError = std::max(maxError, glm::length(got - expected) / glm::length(expected));
      maxDepthError = std::max(maxDepthError, std::abs(out.clipW(x, y) - h.t) / h.t);
      // What screen-space (affine) interpolation would give at this pixel.
      const auto ndc = [&](const Vec3& p) {
        return glm::dvec2(p.x / (-p.z * cam.tanHalf * cam.aspect()), p.y / (-p.z * cam.tanHalf));
      };
      const glm::dvec2 s0 = ndc(cs[0]), s1 = ndc(cs[1]), s2 = ndc(cs[2]);
      const glm::dvec2 q(2.0 * (x + 0.5) / cam.width - 1.0, 1.0 - 2.0 * (y + 0.5) / cam.height);
      const auto cross2 = [](const glm::dvec2& a, const glm::dvec2& b) { return a.x * b.y - a.y * b.x; };
      const double area = cross2(s1 - s0, s2 - s0);
      const double l1 = cross2(q - s0, s2 - s0) / area, l2 = cross2(s1 - s0, q - s0) / area;
      const glm::dvec3 affine = (1.0 - l1 - l2) * p0 + l1 * p1 + l2 * p2;
      maxAffineError = std::max(maxAffineError, glm::length(affine - expected) / glm::length(expected));
    }
  EXPECT_GT(covered, 3000);
  EXPECT_EQ(coverageMismatch, 0);
  // Measured: ~1e-7 (float output of a double solve); affine interpolation errs by ~0.5.
  EXPECT_LT(maxError, 2e-6);
  EXPECT_LT(maxDepthError, 2e-6);
  EXPECT_GT(maxAffineError, 0.1);
}

// Two interpenetrating triangles: A at constant depth 0, B tilted from -0.5 to +0.5 across x (its
// depth at a pixel centre x + 0.5 is -0.5 + (x + 0.5 - 5) / 120), drawn A first (order 0) or B first.
Mesh2 interpenetratingTriangles(int order) {
  Mesh2 m;
  m.width = 130;
  m.height = 70;
  const double x0 = 5.0, x1 = 125.0;
  const uint32_t a0 = m.addRasterVertex(x0, 5), a1 = m.addRasterVertex(x1, 5), a2 = m.addRasterVertex(65, 65);
  const uint32_t b0 = m.addRasterVertex(x0, 65, -0.5f), b1 = m.addRasterVertex(x1, 65, 0.5f),
                 b2 = m.addRasterVertex(65, 2, 0.0f);
  const glm::uvec3 A(a0, a1, a2), B(b0, b1, b2);
  m.triangles = order == 0 ? std::vector<glm::uvec3>{A, B} : std::vector<glm::uvec3>{B, A};
  return m;
}

// One triangle three times over, its corners in three orders.
Mesh2 coplanarDuplicates() {
  Mesh2 m;
  m.width = 100;
  m.height = 90;
  m.addRasterVertex(3.3, 4.1, 0.25f);
  m.addRasterVertex(97.2, 20.7, 0.25f);
  m.addRasterVertex(30.1, 88.8, 0.25f);
  m.triangles = {{0, 1, 2}, {0, 2, 1}, {1, 2, 0}};
  return m;
}

TEST(Rasterizer, DepthTestKeepsTheNearestSurfaceAndBreaksTiesByInputOrder) {
  // The analytic winner at each pixel centre is the smaller depth; far from the intersection line
  // the result must match in both drawing orders.
  for (int order = 0; order < 2; ++order) {
    const Mesh2 m = interpenetratingTriangles(order);
    const int idA = order == 0 ? 0 : 1, idB = 1 - idA;
    const RasterOutput out = rasterize(m.input());
    const Image<int> count = coverageCount(m);
    int checked = 0;
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x) {
        const double zB = -0.5 + ((x + 0.5) - 5.0) / 120.0;  // B's depth is linear in x only
        if (count(x, y) == 2 && std::abs(zB) > 1e-3) {
          EXPECT_EQ(out.triangle(x, y), zB < 0.0 ? idB : idA) << x << "," << y;
          EXPECT_NEAR(out.depth(x, y), std::min(zB, 0.0), 1e-5);
          ++checked;
        }
      }
    EXPECT_GT(checked, 1000);
  }
  // Coplanar duplicates: the first triangle in the input wins every pixel.
  Mesh2 m = coplanarDuplicates();
  m.payloads = {10, 11, 12};
  const RasterOutput out = rasterize(m.input());
  int covered = 0;
  for (size_t i = 0; i < out.triangle.size(); ++i) {
    if (out.triangle[i] < 0) continue;
    ++covered;
    EXPECT_EQ(out.triangle[i], 0);
    EXPECT_EQ(out.payload[i], 10);
  }
  EXPECT_GT(covered, 3000);
}

// The same pass's visitor with the farthest layer: per pixel the deepest covering triangle and its
// barycentrics (giving the analytic max of the two depths), the nearest layer unchanged, and ties to
// the first in input order.
TEST(Rasterizer, FarthestLayerKeepsTheDeepestSurfaceAndLeavesTheNearestAsItWas) {
  for (int order = 0; order < 2; ++order) {
    const Mesh2 m = interpenetratingTriangles(order);
    const int idA = order == 0 ? 0 : 1, idB = 1 - idA;
    const RasterOutput nearest = rasterize(m.input());
    Image<int32_t> farTriangle(m.width, m.height, -2), nearTriangle(m.width, m.height, -2);
    Image<float> farKey(m.width, m.height, 0.0f);
    RasterInput in = m.input();
    in.farthestLayer = true;
    rasterize(in, [&](const TileSamples& t) {
      for (int j = 0; j < t.height; ++j)
        for (int i = 0; i < t.width; ++i) {
          const int k = j * kTileSize + i;
          farTriangle(t.x0 + i, t.y0 + j) = t.farTriangle[k];
          nearTriangle(t.x0 + i, t.y0 + j) = t.triangle[k];
          if (t.farTriangle[k] < 0) continue;
          // The far triangle's depth at the pixel, from its barycentrics.
          const glm::uvec3& v = m.triangles[static_cast<size_t>(t.farTriangle[k])];
          const Vec3& b = t.farBarycentrics[k];
          farKey(t.x0 + i, t.y0 + j) = b.x * m.clip[v.x].z + b.y * m.clip[v.y].z + b.z * m.clip[v.z].z;
        }
    });
    const Image<int> count = coverageCount(m);
    int checked = 0;
    for (int y = 0; y < m.height; ++y)
      for (int x = 0; x < m.width; ++x) {
        ASSERT_EQ(nearTriangle(x, y), nearest.triangle(x, y)) << x << "," << y;
        if (count(x, y) == 0) {
          ASSERT_EQ(farTriangle(x, y), -1) << x << "," << y;
          continue;
        }
        if (count(x, y) == 1) {
          ASSERT_EQ(farTriangle(x, y), nearest.triangle(x, y)) << x << "," << y;
          continue;
        }
        const double zB = -0.5 + ((x + 0.5) - 5.0) / 120.0;
        if (std::abs(zB) > 1e-3) {
          EXPECT_EQ(farTriangle(x, y), zB > 0.0 ? idB : idA) << x << "," << y;
          EXPECT_NEAR(farKey(x, y), std::max(zB, 0.0), 1e-5);
          ++checked;
        }
      }
    EXPECT_GT(checked, 1000);
  }
  // Coplanar duplicates: the first triangle in the input is the deepest too.
  Mesh2 m = coplanarDuplicates();
  RasterInput in = m.input();
  in.farthestLayer = true;
  std::atomic<int> covered = 0, others = 0;
  rasterize(in, [&](const TileSamples& t) {
    for (int j = 0; j < t.height; ++j)
      for (int i = 0; i < t.width; ++i) {
        const int32_t far = t.farTriangle[j * kTileSize + i];
        covered += far >= 0;
        others += far > 0;
      }
  });
  EXPECT_GT(covered.load(), 3000);
  EXPECT_EQ(others.load(), 0);
}

TEST(Rasterizer, ClipsATriangleCrossingTheCameraPlane) {
  const Perspective cam;
  // One vertex behind the camera (view depth -3): only the part in front of the near plane shows,
  // and it reaches the image border. Expected coverage and positions from ray casting.
  const std::array<Vec3, 3> cs{Vec3(-1.0f, -1.0f, -2.0f), Vec3(1.5f, -0.8f, -2.5f), Vec3(0.2f, 0.6f, 3.0f)};
  const Mesh2 m = perspectiveTriangle(cam, cs);
  ASSERT_LT(m.clip[2].w, 0.0f);
  const RasterOutput out = rasterize(m.input());
  const glm::dvec3 p0(cs[0]), p1(cs[1]), p2(cs[2]);
  int covered = 0, mismatch = 0;
  double maxError = 0.0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const glm::dvec3 d = cam.rayDirection(x, y);
      const Hit h = intersect(d, p0, p1, p2);
      const bool expected = h.hit && h.t >= cam.zNear;
      const bool rasterHit = out.triangle(x, y) == 0;
      if (std::abs(h.edgeDistance) > 1e-3) mismatch += expected != rasterHit;
      if (!rasterHit || !h.hit) continue;
      ++covered;
      const glm::dvec3 got(out.attributes[0](x, y), out.attributes[1](x, y), out.attributes[2](x, y));
      maxError = std::max(maxError, glm::length(got - h.t * d) / glm::length(h.t * d));
    }
  EXPECT_EQ(mismatch, 0);
  EXPECT_GT(covered, 2000);  // measured: 2479
  EXPECT_LT(maxError, 2e-6);
  // The triangle reaches the image's bottom row (it extends towards the camera and beyond).
  int bottom = 0;
  for (int x = 0; x < cam.width; ++x) bottom += out.triangle(x, cam.height - 1) == 0;
  EXPECT_GT(bottom, 10);
}

TEST(Rasterizer, HugeTrianglesAreClippedToTheGuardBand) {
  // Vertices 1e7 viewport widths away: the triangle covers the whole image, each pixel once, at
  // the plane's depth. A triangle with a non-finite vertex is skipped, not drawn or crashed on.
  Mesh2 m;
  m.width = 200;
  m.height = 150;
  m.clip = {Vec4(-3e7f, -2e7f, 0.1f, 1.0f), Vec4(4e7f, -1e7f, 0.1f, 1.0f), Vec4(1e5f, 5e7f, 0.1f, 1.0f),
            Vec4(0.0f, 0.0f, 0.0f, 1.0f),   Vec4(NAN, 0.0f, 0.0f, 1.0f),   Vec4(0.5f, 0.5f, 0.0f, 1.0f)};
  m.triangles = {{0, 1, 2}, {3, 4, 5}};
  const Image<int> count = coverageCount(m);
  const RasterOutput out = rasterize(m.input());
  for (int y = 0; y < m.height; ++y)
    for (int x = 0; x < m.width; ++x) {
      ASSERT_EQ(count(x, y), 1) << x << "," << y;
      EXPECT_EQ(out.triangle(x, y), 0);
      EXPECT_NEAR(out.depth(x, y), 0.1f, 1e-6f);
    }
}

TEST(Rasterizer, OutputIsBitIdenticalForAnyThreadCount) {
  Mesh2 m;
  m.width = 300;
  m.height = 220;
  m.attributeCount = 2;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> pos(-1.2f, 1.2f), off(-0.08f, 0.08f), depth(0.5f, 20.0f);
  for (int t = 0; t < 20000; ++t) {
    const float cx = pos(rng), cy = pos(rng);
    for (int k = 0; k < 3; ++k) {
      const float w = depth(rng);
      m.clip.emplace_back((cx + off(rng)) * w, (cy + off(rng)) * w, -0.1f, w);
      m.attributes.push_back(pos(rng));
      m.attributes.push_back(w);
    }
    m.triangles.emplace_back(3 * t, 3 * t + 1, 3 * t + 2);
    m.payloads.push_back(t % 17);
  }
  auto run = [&](int threads) {
    // Allow more threads than the machine has cores, so that several really run.
    tbb::global_control allow(tbb::global_control::max_allowed_parallelism, threads);
    tbb::task_arena arena(threads);
    RasterOutput out;
    arena.execute([&] { out = rasterize(m.input()); });
    return out;
  };
  const RasterOutput one = run(1), four = run(4);
  auto same = [](const auto& a, const auto& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0;
  };
  EXPECT_TRUE(same(one.depth, four.depth));
  EXPECT_TRUE(same(one.clipW, four.clipW));
  EXPECT_TRUE(same(one.triangle, four.triangle));
  EXPECT_TRUE(same(one.payload, four.payload));
  ASSERT_EQ(one.attributes.size(), 2u);
  EXPECT_TRUE(same(one.attributes[0], four.attributes[0]));
  EXPECT_TRUE(same(one.attributes[1], four.attributes[1]));
  int covered = 0;
  for (int32_t t : one.triangle) covered += t >= 0;
  EXPECT_GT(covered, 50000);
}

TEST(Rasterizer, RejectsMalformedInput) {
  Mesh2 m;
  m.width = 10;
  m.height = 10;
  m.addRasterVertex(1, 1);
  m.addRasterVertex(8, 1);
  m.addRasterVertex(1, 8);
  m.triangles = {{0, 1, 3}};
  try {
    rasterize(m.input());
    FAIL() << "expected an Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 0 references vertex 3"), std::string::npos) << e.what();
  }
  m.triangles = {{0, 1, 2}};
  m.attributeCount = 2;
  m.attributes = {1.0f, 2.0f};
  EXPECT_THROW(rasterize(m.input()), Error);
  m.attributeCount = 0;
  m.attributes.clear();
  m.payloads = {1, 2};
  EXPECT_THROW(rasterize(m.input()), Error);
  m.payloads.clear();
  m.width = 0;
  EXPECT_THROW(rasterize(m.input()), Error);
  m.width = kMaxImageSize + 1;
  EXPECT_THROW(rasterize(m.input()), Error);
}

}  // namespace
}  // namespace penumbra::raster
