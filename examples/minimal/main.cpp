// Loads a built-in scene (or a scene file), runs pcss (512 x 512 map) and the reference for its first
// light on a 256 x 256 G-buffer, and prints pcss's RMSE8 against the reference.
//
//   minimal [scene]        scene: a built-in name (penumbra scenes) or a scene file; default torus
#include <cstdio>
#include <string>

#include "penumbra/error.h"
#include "penumbra/metrics.h"
#include "penumbra/raster.h"
#include "penumbra/reference.h"
#include "penumbra/scene_io.h"
#include "penumbra/techniques/shadow_map.h"

int main(int argc, char** argv) {
  try {
    const std::string name = argc > 1 ? argv[1] : "torus";
    const penumbra::Scene scene = penumbra::loadScene(name);
    if (scene.lights.empty()) throw penumbra::Error(name + ": the scene has no light");
    const penumbra::Light& light = scene.lights.front();
    const penumbra::GBuffer gbuffer = penumbra::renderGBuffer(scene, 256, 256);

    // A technique from its typed options (penumbra/techniques/*.h): the defaults but for the map's size.
    // The same by name: penumbra::createTechnique("pcss", params) with map_size=512.
    penumbra::PcssOptions pcssOptions;
    pcssOptions.lightMap.size = 512;
    const std::unique_ptr<penumbra::ShadowTechnique> pcss = penumbra::makeTechnique(pcssOptions);
    penumbra::Image<float> v;
    pcss->prepare(scene, light);
    pcss->visibility(gbuffer, v);

    // The reference, typed: 64 rays per pixel, seed 1.
    penumbra::ReferenceOptions options;
    options.samplesPerPixel = 64;
    penumbra::ReferenceTechnique reference(options);
    penumbra::Image<float> truth;
    reference.prepare(scene, light);
    reference.visibility(gbuffer, truth);

    const penumbra::ErrorStats error = penumbra::compareVisibility(v, truth, penumbra::errorMask(gbuffer, light));
    std::printf("%s: pcss RMSE8 %.2f, penumbra RMSE8 %.2f (reference at %u spp)\n", name.c_str(), error.rmse8,
                error.penumbraRmse8, options.samplesPerPixel);
    return 0;
  } catch (const penumbra::Error& e) {
    std::fprintf(stderr, "minimal: %s\n", e.what());
    return 1;
  }
}
