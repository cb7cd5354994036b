// Pictures and picks for comparison reports: the diverging colour map of signed error maps
// (blue = V below the reference, white = equal, red = above), the signed error image itself, and
// the image row a scan-line profile should follow (the one crossing the most penumbra).
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "penumbra/image.h"
#include "penumbra/math.h"

namespace penumbra {

using Srgb8 = std::array<uint8_t, 3>;

// The colour map's stops: t in [-1, 1] -> sRGB, ascending in t, symmetric about t = 0 (white).
// ColorBrewer's 11-class RdBu (Brewer, colorbrewer2.org), blue for negative: perceptually ordered
// in each half and readable by people with red-green colour blindness.
const std::vector<std::pair<double, Srgb8>>& divergingStops();
// Piecewise-linear in sRGB between the stops; t beyond [-1, 1] saturates (an error map's legend
// says so), NaN gives the "not measured" colour.
Srgb8 divergingColor(double t);
// Colour of pixels outside the error mask (not measured): a grey no stop uses.
Srgb8 unmeasuredColor();

// Linear RGB (for writePng) of (v - reference) / range through divergingColor where mask is set,
// unmeasuredColor elsewhere. range > 0 in V units; sizes must match. Throws Error otherwise.
Image<Vec3> signedErrorMap(const Image<float>& v, const Image<float>& reference, const Image<uint8_t>& mask,
                           double range);

// The row with the most mask pixels whose reference V is in the penumbra (0.01, 0.99) (docs/architecture.md,
// "Vocabulary"); ties go to the topmost row; with no penumbra at all, the middle row.
int mostPenumbraRow(const Image<float>& reference, const Image<uint8_t>& mask);

}  // namespace penumbra
