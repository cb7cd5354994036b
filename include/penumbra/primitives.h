// Built-in primitives as triangle meshes in their local frame (to be transformed by the scene file).
// Closed primitives are watertight (shared vertices) and wound counter-clockwise seen from outside.
#pragma once

#include "penumbra/math.h"
#include "penumbra/scene.h"

namespace penumbra {

Mesh makePlane(float sizeX, float sizeZ);                //!< in y = 0, normal +y, centred, 2 triangles
Mesh makeBox(const Vec3& size);                          //!< centred, closed
Mesh makeSphere(float radius, int segments, int rings);  //!< centred UV sphere, closed
Mesh makeTorus(float majorRadius, float minorRadius, int majorSegments, int minorSegments);  //!< axis +y, closed
Mesh makeCylinder(float radius, float height, int segments);     //!< axis +y, centred, capped, closed
Mesh makeTriangle(const Vec3& a, const Vec3& b, const Vec3& c);  //!< one triangle, as given

// Applies an affine transform to positions and (inverse-transpose) to normals.
void transformMesh(Mesh& mesh, const Mat4& wsFromObject);

}  // namespace penumbra
