// The Python module `penumbra` (its compiled part, penumbra._penumbra; python/penumbra/__init__.py is
// the package): scenes, the registry, the G-buffer, techniques and the reference, the metric, shading
// and the CLI's commands, with numpy arrays in and out. Images come out without a copy: each numpy
// array owns the C++ image it views (or, for a G-buffer's fields, keeps its G-buffer alive). Every
// penumbra::Error becomes penumbra.Error with the same message.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "cli.h"
#include "penumbra/engine.h"
#include "penumbra/error.h"
#include "penumbra/metrics.h"
#include "penumbra/raster.h"
#include "penumbra/reference.h"
#include "penumbra/registry.h"
#include "penumbra/report.h"
#include "penumbra/scene_io.h"
#include "penumbra/shade.h"

namespace py = pybind11;
using namespace penumbra;

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;
using IdArray = py::array_t<int32_t, py::array::c_style | py::array::forcecast>;

namespace {

// A numpy view of `image` (rows, columns[, channels] of T), owned by a capsule that deletes it.
template <class T>
py::array ownedArray(Image<T>&& image, int channels = 1) {
  auto held = std::make_unique<Image<T>>(std::move(image));
  Image<T>* owned = held.get();
  py::capsule free(owned, [](void* p) { delete static_cast<Image<T>*>(p); });
  held.release();  // the capsule owns it now
  const auto h = static_cast<py::ssize_t>(owned->height()), w = static_cast<py::ssize_t>(owned->width());
  if constexpr (std::is_arithmetic_v<T>) {
    return py::array_t<T>({h, w}, owned->data(), free);
  } else {
    using Scalar = typename T::value_type;
    return py::array_t<Scalar>({h, w, static_cast<py::ssize_t>(channels)}, reinterpret_cast<Scalar*>(owned->data()),
                               free);
  }
}

// A numpy view of one field of a G-buffer held by a Python object, which it keeps alive.
template <class Scalar, class T>
py::array fieldView(const Image<T>& image, int channels, py::handle owner) {
  const auto h = static_cast<py::ssize_t>(image.height()), w = static_cast<py::ssize_t>(image.width());
  const auto* data = reinterpret_cast<const Scalar*>(image.data());
  py::array_t<Scalar> a = channels == 1 ? py::array_t<Scalar>({h, w}, data, owner)
                                        : py::array_t<Scalar>({h, w, static_cast<py::ssize_t>(channels)}, data, owner);
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;  // a view, read-only
  return a;
}

// An (h, w) float32 array as an image (copied: the metric and shading read images).
Image<float> imageFrom(const py::array_t<float, py::array::c_style | py::array::forcecast>& a, const char* what) {
  if (a.ndim() != 2)
    throw Error(std::string(what) + ": expected a 2-D array (height, width) of V, got " + std::to_string(a.ndim()) +
                " dimensions");
  Image<float> image(static_cast<int>(a.shape(1)), static_cast<int>(a.shape(0)));
  std::copy(a.data(), a.data() + a.size(), image.data());
  return image;
}

const Light& lightOf(const Scene& scene, int index) {
  if (index < 0 || index >= static_cast<int>(scene.lights.size()))
    throw Error(scene.source + ": light " + std::to_string(index) + " does not exist (the scene has " +
                std::to_string(scene.lights.size()) + " light(s), 0-based)");
  return scene.lights[static_cast<size_t>(index)];
}

void checkSize(const GBuffer& gbuffer, const Image<float>& v, const char* what) {
  if (v.width() != gbuffer.width() || v.height() != gbuffer.height())
    throw Error(std::string(what) + ": V is " + std::to_string(v.height()) + " x " + std::to_string(v.width()) +
                " (height x width), the G-buffer " + std::to_string(gbuffer.height()) + " x " +
                std::to_string(gbuffer.width()));
}

py::object paramValue(const ParamValue& value) {
  return std::visit([](const auto& v) -> py::object { return py::cast(v); }, value);
}

// A technique made by name, as the CLI makes it: parameters validated against its schema when it is
// made, the ones the scene file gives for it applied under the caller's. One thread at a time uses
// it: the passes run without the GIL, under the technique's own lock, so a second thread waits.
class Technique {
 public:
  Technique(std::string name, const py::dict& params) : name_(std::move(name)) {
    const TechniqueInfo& info = findTechnique(name_);  // an unknown name fails here, listing the known ones
    for (const auto& [key, value] : params) given_.set(py::str(key), paramValueOf(value), "Python");
    resolveParams(name_, info.params, given_);  // a bad value fails here, with the CLI's message
  }

  void prepare(const Scene& scene, int light) {
    const Light& l = lightOf(scene, light);
    py::gil_scoped_release release;
    std::lock_guard lock(mutex_);
    // One instance while the scene file is the same, so that what a technique keeps between frames
    // (BVHs, edge adjacency, its buffers) is kept, as in `penumbra bench`.
    if (!technique_ || preparedFor_ != scene.source) {
      ParamSet merged;
      if (const auto it = scene.techniqueParams.find(name_); it != scene.techniqueParams.end()) merged = it->second;
      for (const auto& [key, entry] : given_.entries()) merged.set(key, entry.value, entry.source);
      technique_ = createTechnique(name_, merged);
      preparedFor_ = scene.source;
    }
    technique_->prepare(scene, l);
  }

  py::array visibility(const GBuffer& gbuffer) {
    Image<float> v;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      if (!technique_) throw Error(name_ + ": visibility() called before prepare(scene, light)");
      technique_->visibility(gbuffer, v);
    }
    return ownedArray(std::move(v));
  }

  py::object standardError() {
    Image<float> copy;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      const auto* reference = dynamic_cast<const ReferenceTechnique*>(technique_.get());
      if (!reference) return py::none();
      copy = reference->standardError();
    }
    return ownedArray(std::move(copy));
  }

  py::dict stats() {
    std::vector<std::pair<std::string, double>> values;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      if (technique_) values = technique_->stats();
    }
    py::dict d;
    for (const auto& [key, value] : values) d[py::str(key)] = value;
    return d;
  }

  py::dict timings() {
    PassTimings values;
    {
      py::gil_scoped_release release;
      std::lock_guard lock(mutex_);
      if (technique_) values = technique_->timings();
    }
    py::dict d;
    for (const auto& [pass, ms] : values.passes) d[py::str(pass)] = ms;
    return d;
  }

  const std::string& name() const { return name_; }

 private:
  // A keyword argument's value as a parameter value: bools (numpy's too), integers and floats by their
  // Python protocols (numpy scalars included), None as "auto", anything else by its text.
  static ParamValue paramValueOf(const py::handle& value) {
    if (value.is_none()) return std::string("auto");
    if (py::isinstance<py::bool_>(value) ||
        py::str(py::type::of(value).attr("__name__")).cast<std::string>() == "bool_")
      return value.cast<bool>();
    if (py::hasattr(value, "__index__")) return value.attr("__index__")().cast<int64_t>();
    if (py::isinstance<py::float_>(value) || py::hasattr(value, "__float__")) return value.cast<double>();
    return std::string(py::str(value));
  }

  std::string name_;
  ParamSet given_;
  std::mutex mutex_;  //!< held, without the GIL, while technique_ is used
  std::unique_ptr<ShadowTechnique> technique_;
  std::string preparedFor_;  //!< the source of the scene technique_ was made for
};

py::dict errorDict(const ErrorStats& e) {
  py::dict d;
  d["rmse8"] = e.rmse8;
  d["penumbra_rmse8"] = e.penumbraRmse8;
  d["max_error"] = e.maxAbsError;
  d["mask_pixels"] = e.maskPixels;
  d["penumbra_pixels"] = e.penumbraPixels;
  d["umbra_leaks"] = e.umbraLeaks;
  d["speckle"] = e.speckle;
  return d;
}

}  // namespace

PYBIND11_MODULE(_penumbra, m) {
  m.doc() = "penumbra: soft shadows from area lights, measured against a ray-traced reference";
  m.attr("__version__") = PENUMBRA_VERSION;
  py::register_exception<Error>(m, "Error", PyExc_ValueError);

  py::class_<Scene>(m, "Scene", "A scene: meshes, camera, lights (load_scene)")
      .def_readonly("name", &Scene::name)
      .def_readonly("source", &Scene::source)
      .def_property_readonly("lights",
                             [](const Scene& s) {
                               std::vector<std::string> lights;
                               for (const Light& l : s.lights) lights.push_back(describeLight(l));
                               return lights;
                             })
      .def_property_readonly("width", [](const Scene& s) { return s.image.width; })
      .def_property_readonly("height", [](const Scene& s) { return s.image.height; })
      .def_property_readonly("triangles", &Scene::triangleCount)
      .def("__repr__", [](const Scene& s) { return "<penumbra.Scene " + s.name + " (" + s.source + ")>"; });

  m.def(
      "load_scene",
      [](const std::string& nameOrPath) {
        Scene scene = loadScene(nameOrPath);
        scene.declareGeometry();  // Python reads a scene's meshes and never changes them
        return scene;
      },
      py::arg("name_or_path"), "A built-in scene by name (scenes()) or a JSON scene file");
  m.def(
      "scenes",
      [] {
        std::vector<py::dict> out;
        for (const BuiltinScene& s : builtinScenes()) {
          py::dict d;
          d["name"] = s.name;
          d["description"] = s.description;
          out.push_back(d);
        }
        return out;
      },
      "The built-in scenes: name and description");
  m.def(
      "techniques",
      [] {
        std::vector<py::dict> out;
        for (const TechniqueInfo& info : techniqueRegistry()) {
          py::dict d;
          d["name"] = info.name;
          d["summary"] = info.summary;
          d["source"] = info.source;
          d["lights"] = info.lights;
          std::vector<py::dict> params;
          for (const ParamSpec& p : info.params) {
            py::dict q;
            q["name"] = p.name;
            q["type"] = std::string(toString(p.type));
            q["default"] = p.autoDefault ? py::object(py::str("auto")) : paramValue(p.defaultValue);
            q["min"] = p.min ? py::object(py::float_(*p.min)) : py::object(py::none());
            q["max"] = p.max ? py::object(py::float_(*p.max)) : py::object(py::none());
            q["choices"] = p.choices;
            q["unit"] = p.unit;
            q["help"] = p.help;
            params.push_back(q);
          }
          d["params"] = params;
          out.push_back(d);
        }
        return out;
      },
      "Every technique with its parameters: name, type, default, min, max, choices, unit, help");

  py::class_<GBuffer>(m, "GBuffer", "The camera G-buffer; its fields are read-only numpy views")
      .def_property_readonly("width", &GBuffer::width)
      .def_property_readonly("height", &GBuffer::height)
      .def_property_readonly(
          "position", [](py::object self) { return fieldView<float>(self.cast<const GBuffer&>().wsPosition, 3, self); })
      .def_property_readonly(
          "normal", [](py::object self) { return fieldView<float>(self.cast<const GBuffer&>().wsNormal, 3, self); })
      .def_property_readonly(
          "geometric_normal",
          [](py::object self) { return fieldView<float>(self.cast<const GBuffer&>().wsGeometricNormal, 3, self); })
      .def_property_readonly(
          "object_id",
          [](py::object self) { return fieldView<int32_t>(self.cast<const GBuffer&>().objectId, 1, self); })
      .def_property_readonly(
          "depth", [](py::object self) { return fieldView<float>(self.cast<const GBuffer&>().csDepth, 1, self); });
  m.def(
      "render_gbuffer",
      [](const Scene& scene, int width, int height) {
        if (width < 1 || height < 1 || width > 16384 || height > 16384)
          throw Error("render_gbuffer: width and height must be in [1, 16384], got " + std::to_string(width) + " x " +
                      std::to_string(height));
        py::gil_scoped_release release;
        return renderGBuffer(scene, width, height);
      },
      py::arg("scene"), py::arg("width"), py::arg("height"), "Rasterizes the scene's camera view");

  m.def(
      "make_gbuffer",
      [](const Scene& scene, const FloatArray& position, const FloatArray& normal, const IdArray& objectId,
         const std::optional<FloatArray>& depth, const std::optional<FloatArray>& geometricNormal) {
        // The caller's own G-buffer of the scene (a renderer of its own, of any size), as engine.h takes
        // it: the scene gives the camera and the meshes' ids.
        if (objectId.ndim() != 2)
          throw Error("make_gbuffer: object_id: expected a 2-D array (height, width) of int32 ids");
        const auto h = objectId.shape(0), w = objectId.shape(1);
        auto check = [&](const FloatArray& a, int channels, const char* name) {
          const bool ok = channels == 1 ? a.ndim() == 2 && a.shape(0) == h && a.shape(1) == w
                                        : a.ndim() == 3 && a.shape(0) == h && a.shape(1) == w && a.shape(2) == channels;
          if (!ok)
            throw Error(std::string("make_gbuffer: ") + name + ": expected shape (" + std::to_string(h) + ", " +
                        std::to_string(w) + (channels == 1 ? ")" : ", 3)") + ", as object_id");
          return std::span<const float>(a.data(), static_cast<size_t>(a.size()));
        };
        EngineGBuffer buffers;
        buffers.width = static_cast<int>(w);
        buffers.height = static_cast<int>(h);
        buffers.wsPosition = check(position, 3, "position");
        buffers.wsNormal = check(normal, 3, "normal");
        buffers.objectId = std::span<const int32_t>(objectId.data(), static_cast<size_t>(objectId.size()));
        if (depth) buffers.csDepth = check(*depth, 1, "depth");
        if (geometricNormal) buffers.wsGeometricNormal = check(*geometricNormal, 3, "geometric_normal");
        std::vector<EngineMesh> meshes;
        for (const Object& o : scene.objects) meshes.push_back({o.id, {}, {}});
        py::gil_scoped_release release;
        return makeGBuffer(buffers, scene.camera, meshes);
      },
      py::arg("scene"), py::arg("position"), py::arg("normal"), py::arg("object_id"), py::arg("depth") = py::none(),
      py::arg("geometric_normal") = py::none(),
      "A G-buffer of the scene from your own arrays: position and normal (height, width, 3), object_id "
      "(height, width; -1 where a pixel sees nothing); depth and geometric_normal optional");

  py::class_<Technique>(m, "Technique", "A technique by name with parameters (techniques() lists them)")
      .def(py::init([](const std::string& name, const py::kwargs& params) {
             return std::make_unique<Technique>(name, params);
           }),
           py::arg("name"))
      .def_property_readonly("name", &Technique::name)
      .def("prepare", &Technique::prepare, py::arg("scene"), py::arg("light") = 0,
           "The light-space work for one light of the scene (maps, BVHs)")
      .def("visibility", &Technique::visibility, py::arg("gbuffer"), "V per pixel, float32 (height, width)")
      .def_property_readonly("standard_error", &Technique::standardError,
                             "the reference's per-pixel standard error of V (None for other techniques)")
      .def("stats", &Technique::stats)
      .def("timings", &Technique::timings, "milliseconds of the last prepare and visibility passes");

  m.def(
      "error_mask",
      [](const GBuffer& gbuffer, const Scene& scene, int light) {
        return ownedArray(errorMask(gbuffer, lightOf(scene, light)));
      },
      py::arg("gbuffer"), py::arg("scene"), py::arg("light") = 0,
      "1 where the pixel sees geometry facing the light's centre: where errors are counted");
  m.def(
      "compare_visibility",
      [](const py::array_t<float, py::array::c_style | py::array::forcecast>& v,
         const py::array_t<float, py::array::c_style | py::array::forcecast>& reference,
         const py::array_t<uint8_t, py::array::c_style | py::array::forcecast>& mask) {
        const Image<float> a = imageFrom(v, "compare_visibility: v"),
                           b = imageFrom(reference, "compare_visibility: reference");
        if (mask.ndim() != 2 || mask.shape(0) != a.height() || mask.shape(1) != a.width() || b.width() != a.width() ||
            b.height() != a.height())
          throw Error("compare_visibility: v, reference and mask must have one shape (height, width)");
        Image<uint8_t> m8(a.width(), a.height());
        std::copy(mask.data(), mask.data() + mask.size(), m8.data());
        return errorDict(compareVisibility(a, b, m8));
      },
      py::arg("v"), py::arg("reference"), py::arg("mask"),
      "RMSE8, penumbra RMSE8, max error, umbra leaks and speckle of V against the reference over the mask");
  m.def(
      "shade",
      [](const Scene& scene, const GBuffer& gbuffer,
         const py::array_t<float, py::array::c_style | py::array::forcecast>& v, int light) {
        const Image<float> image = imageFrom(v, "shade: v");
        checkSize(gbuffer, image, "shade");
        return ownedArray(shade(scene, lightOf(scene, light), gbuffer, image), 3);
      },
      py::arg("scene"), py::arg("gbuffer"), py::arg("v"), py::arg("light") = 0,
      "The shaded image, linear RGB float32 (height, width, 3), exposure-normalized");
  m.def(
      "cli",
      [](const std::vector<std::string>& args) {
        std::vector<const char*> argv = {"penumbra"};
        for (const std::string& a : args) argv.push_back(a.c_str());
        py::gil_scoped_release release;
        return cli::runCommandLine(static_cast<int>(argv.size()), argv.data(), true);
      },
      py::arg("args"),
      "Runs one penumbra command line in this process (['compare', '--scene', 'torus', ...]); returns its exit "
      "code, raises penumbra.Error on bad input");
}
