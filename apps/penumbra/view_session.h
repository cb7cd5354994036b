// What `penumbra view` renders (view.cpp serves it over HTTP): one scene and its G-buffer, the
// technique and parameters the page chose, and a reference that accumulates batch after batch while
// nothing moves and starts again when anything does. No HTTP here, so that the tests and
// `penumbra view --measure-frames` drive it directly.
//
// A frame goes to the page as two images, the technique's side and the reference's side of the split
// view, in the display the page chose (V, shaded, signed error), with the pass times and the error
// against the reference as it stands. The images are the raw 8-bit pixels (the default: over loopback
// the bytes cost nothing, while encoding a 512 x 512 PNG takes longer than most techniques' whole
// frame, which the "encode" pass time shows with --encoding png) or PNG files.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "penumbra/camera.h"
#include "penumbra/gbuffer.h"
#include "penumbra/image.h"
#include "penumbra/light.h"
#include "penumbra/metrics.h"
#include "penumbra/params.h"
#include "penumbra/reference.h"
#include "penumbra/scene.h"
#include "penumbra/technique.h"

namespace penumbra::cli {

enum class ViewDisplay { Visibility, Shaded, Error };
enum class FrameEncoding { Raw, Png };

// Everything one frame depends on, as the page sends it (ViewSession::parseRequest).
struct ViewRequest {
  Camera camera;
  int lightIndex = 0;  //!< which of the scene's lights the page started from
  LightShape shape = LightShape::Sphere;
  // Local lights: the centre. Directional: a point whose direction from the scene's centre is the
  // direction to the light.
  Vec3 lightPosition{0.0f};
  // Sphere and disk: radius; rect: half-edge; segment: half-length; polygon: the scene's polygon scaled
  // to this extent (world units). Directional: angular diameter, degrees.
  float lightSize = 0.0f;
  std::string technique;
  std::map<std::string, std::string> params;  //!< as typed in the page, checked by the technique's schema
  ViewDisplay display = ViewDisplay::Visibility;
};

struct ViewImage {
  int width = 0, height = 0;
  int channels = 1;  //!< 1 (gray) or 3 (sRGB)
  bool png = false;  //!< bytes hold a PNG file; otherwise the raw rows of 8-bit pixels
  std::vector<uint8_t> bytes;
};

struct ViewFrame {
  ViewDisplay display = ViewDisplay::Visibility;  //!< what the images show
  std::optional<ViewImage> technique;             //!< none when the technique could not run (see techniqueError)
  ViewImage reference;
  std::optional<std::string> techniqueError;           //!< why the technique did not run on this light or scene
  std::vector<std::pair<std::string, double>> passMs;  //!< gbuffer, prepare, visibility, reference, metrics, encode
  bool gbufferCached = false;                          //!< the camera did not move: the last G-buffer was reused
  bool techniqueCached = false;                        //!< nothing it depends on changed: its last V was reused
  std::optional<ErrorStats> error;                     //!< the technique against the reference as it stands
  uint32_t referenceSamples = 0;                       //!< per pixel, accumulated since the view last changed
  uint32_t referenceMaxSamples = 0;
  double referenceStdError = 0.0;  //!< mean standard error of the reference's V over the error mask
};

class ViewSession {
 public:
  struct Options {
    int width = 512, height = 512;
    uint32_t referenceMaxSpp = 1024;  //!< the progressive reference stops here
    FrameEncoding encoding = FrameEncoding::Raw;
  };
  ViewSession(Scene scene, const Options& options);
  ~ViewSession();

  // The page's starting point as JSON: image size, the scene's camera, bounds and lights, every
  // technique with its parameter schema (ranges, units, help), the light shapes.
  std::string setupJson(const std::string& initialTechnique, int initialLight) const;
  // A request from the page's JSON. Throws Error naming the field and what was expected.
  ViewRequest parseRequest(const std::string& json) const;
  // The request as the page would send it for the scene's own camera and light `lightIndex`.
  ViewRequest initialRequest(const std::string& technique, int lightIndex) const;
  // Renders what changed since the last frame: the G-buffer when the camera moved, the technique when
  // the camera, the light, the technique or its parameters changed, and one more batch of the
  // reference (restarted when the camera or light changed). Throws Error for a bad parameter value
  // (the schema's message), an unknown technique or a degenerate light or camera; a technique that
  // cannot take the light is not an error of the frame (ViewFrame::techniqueError).
  ViewFrame render(const ViewRequest& request);
  // The light a request describes. Throws Error for a degenerate one.
  Light makeLight(const ViewRequest& request) const;

  const Scene& scene() const { return scene_; }
  const Options& options() const { return options_; }

 private:
  Scene scene_;
  Options options_;
  Vec3 sceneCentre_{0.0f};
  float sceneRadius_ = 1.0f;
  GBuffer gbuffer_;
  std::optional<Camera> gbufferCamera_;
  // The last request's light and technique (what their outputs were made for).
  std::optional<ViewRequest> lightKey_;
  std::string techniqueName_;
  Params techniqueParams_;
  std::unique_ptr<ShadowTechnique> technique_;
  bool techniqueValid_ = false;
  std::optional<std::string> techniqueError_;
  Image<float> v_;
  Image<uint8_t> mask_;
  // The progressive reference: sums over batches of spp * V and of (spp * standard error)^2.
  ReferenceTechnique reference_;
  Image<float> batchV_;
  Image<double> sumV_, sumVariance_;
  Image<float> referenceV_;
  uint32_t referenceSamples_ = 0, referenceBatches_ = 0, lastBatch_ = 0;
};

// The frame as the page reads it: a 4-byte little-endian length, that many bytes of JSON (the pass
// times, the error, the reference's sample count, and where each image lies), then the images' bytes.
std::string encodeViewFrame(const ViewFrame& frame);

}  // namespace penumbra::cli
