// The Python module `stex` (pybind11), a thin layer over the C++ wrapper include/stex/stex.hpp (and so over
// libstex.so's C API): analyse an exemplar (file or NumPy array), load and save models of any kind, render
// regions into NumPy float32 arrays of shape (H, W, C), point queries, surface-noise point queries. Device work, analysis and file I/O run with the
// GIL released (py::gil_scoped_release), so Python threads can render concurrently (calls on one Context
// serialise inside stex; use one Context per thread for parallel device work).
//
// Errors raise stex.Error (a RuntimeError) with attributes `status` ("STEX_USAGE", ...) and `code` (the C
// status value). Renders check for signals (Ctrl-C raises KeyboardInterrupt between chunks of rows) and call
// an optional progress(fraction) callable: a truthy return value cancels (stex.Error, STEX_CANCELLED); an
// exception raised by it cancels and propagates unchanged.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstdint>
#include <string>
#include <vector>

#include "stex/stex.hpp"

namespace py = pybind11;

namespace {

PyObject* g_error_type = nullptr;  // stex.Error; owned by the module for the life of the process

std::int32_t parse_strategy(const std::string& name) {
  if (name == "auto") return STEX_STRATEGY_AUTO;
  if (name == "splat") return STEX_STRATEGY_SPLAT;
  if (name == "gather") return STEX_STRATEGY_GATHER;
  throw py::value_error("strategy must be 'auto', 'splat' or 'gather', got '" + name + "'");
}

std::int32_t parse_filter(const std::string& name) {
  if (name == "auto") return STEX_FILTER_AUTO;
  if (name == "on") return STEX_FILTER_ON;
  if (name == "off") return STEX_FILTER_OFF;
  throw py::value_error("filter must be 'auto', 'on' or 'off', got '" + name + "'");
}

stex::RenderParams render_params(double mni, std::uint64_t seed, double scale, double cell_factor,
                                 const std::string& strategy, const std::string& filter = "auto") {
  stex::RenderParams p;
  p.mni = mni;
  p.seed = seed;
  p.scale = scale;
  p.cell_factor = cell_factor;
  p.strategy = parse_strategy(strategy);
  p.filter = parse_filter(filter);
  return p;
}

stex::AnalysisParams analysis_params(int support, int iterations, std::uint64_t seed, int order,
                                     bool colour_correction, bool linear) {
  stex::AnalysisParams a;
  a.support = support;
  a.iterations = iterations;
  a.seed = seed;
  a.order = order;
  a.colour_correction = colour_correction ? 1 : 0;
  a.linear = linear ? 1 : 0;
  return a;
}

// Progress for renders: checks signals, then calls the user's callable (if any), with the GIL held. A
// Python exception (KeyboardInterrupt, or raised by the callable) is left set on this thread and cancels the
// render; the caller re-raises it after the render returns.
struct PythonProgress {
  py::object callable;
  bool python_error = false;

  bool operator()(double fraction) {
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      python_error = true;
      return true;
    }
    if (callable.is_none()) return false;
    try {
      py::object result = callable(fraction);
      return PyObject_IsTrue(result.ptr()) == 1;
    } catch (py::error_already_set& e) {
      e.restore();
      python_error = true;
      return true;
    }
  }
};

// Runs a device call with the GIL released and a PythonProgress; re-raises a Python error it recorded.
template <class Call>
void with_progress(const py::object& progress, Call&& call) {
  PythonProgress state{progress};
  try {
    py::gil_scoped_release release;
    call(stex::Context::Progress(std::ref(state)));
  } catch (const stex::Error&) {
    if (state.python_error && PyErr_Occurred()) throw py::error_already_set();
    throw;
  }
}

py::array_t<float> render(stex::Context& ctx, const stex::Model& model, std::int64_t x, std::int64_t y,
                          int width, int height, double mni, std::uint64_t seed, double scale,
                          double cell_factor, const std::string& strategy, const std::string& filter,
                          const py::object& progress) {
  const stex::RenderParams p = render_params(mni, seed, scale, cell_factor, strategy, filter);
  if (width < 1 || height < 1)
    throw py::value_error("width and height must be at least 1, got " + std::to_string(width) + "x" +
                          std::to_string(height));
  if (!model) throw py::value_error("empty model");
  const int nc = model.channels();
  py::array_t<float> out({py::ssize_t(height), py::ssize_t(width), py::ssize_t(nc)});
  float* data = out.mutable_data();
  with_progress(progress, [&](const stex::Context::Progress& fn) {
    ctx.render(model, p, x, y, width, height, data, 0, fn);
  });
  return out;
}

// xy: any array of shape (..., 2) of positions in output-pixel coordinates -> float32 (..., C).
py::array_t<float> eval_points(stex::Context& ctx, const stex::Model& model,
                               const py::array_t<double, py::array::c_style | py::array::forcecast>& xy,
                               double mni, std::uint64_t seed, double scale, double cell_factor) {
  const stex::RenderParams p = render_params(mni, seed, scale, cell_factor, "auto");
  if (!model) throw py::value_error("empty model");
  if (xy.ndim() < 1 || xy.shape(xy.ndim() - 1) != 2)
    throw py::value_error("positions must have shape (..., 2): (x, y) in output-pixel coordinates");
  const std::size_t count = std::size_t(xy.size()) / 2;
  const int nc = model.channels();
  std::vector<py::ssize_t> shape(xy.shape(), xy.shape() + xy.ndim());
  shape.back() = nc;
  py::array_t<float> out(shape);
  const double* in = xy.data();
  float* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    ctx.eval_points(model, p, count, in, data);
  }
  return out;
}

// Surface noise: positions, normals (and tangents, or None) of shape (..., 3), world units -> float32 (..., C).
py::array_t<float> eval_surface_points(stex::Context& ctx, const stex::Model& model,
                                       const py::array_t<double, py::array::c_style | py::array::forcecast>& positions,
                                       const py::array_t<double, py::array::c_style | py::array::forcecast>& normals,
                                       const py::object& tangents_obj, double mni, std::uint64_t seed,
                                       double texel, double cell_factor) {
  stex::SurfaceParams p;
  p.mni = mni;
  p.seed = seed;
  p.texel = texel;
  p.cell_factor = cell_factor;
  if (!model) throw py::value_error("empty model");
  auto same_shape = [](const py::array& a, const py::array& b) {
    if (a.ndim() != b.ndim()) return false;
    for (py::ssize_t i = 0; i < a.ndim(); ++i)
      if (a.shape(i) != b.shape(i)) return false;
    return true;
  };
  if (positions.ndim() < 1 || positions.shape(positions.ndim() - 1) != 3)
    throw py::value_error("positions must have shape (..., 3): (x, y, z) in world units");
  if (!same_shape(positions, normals)) throw py::value_error("normals must have the shape of positions");
  py::array_t<double, py::array::c_style | py::array::forcecast> tangents;
  const bool have_tangents = !tangents_obj.is_none();
  if (have_tangents) {
    tangents = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(tangents_obj);
    if (!tangents) throw py::value_error("tangents must be None or an array of the shape of positions");
    if (!same_shape(positions, tangents)) throw py::value_error("tangents must have the shape of positions");
  }
  const std::size_t count = std::size_t(positions.size()) / 3;
  const int nc = model.channels();
  std::vector<py::ssize_t> shape(positions.shape(), positions.shape() + positions.ndim());
  shape.back() = nc;
  py::array_t<float> out(shape);
  const double* pos = positions.data();
  const double* nrm = normals.data();
  const double* tan = have_tangents ? tangents.data() : nullptr;
  float* data = out.mutable_data();
  {
    py::gil_scoped_release release;
    ctx.eval_surface_points(model, p, count, pos, nrm, tan, data);
  }
  return out;
}

stex::Model analyse_array(const py::array_t<float, py::array::c_style | py::array::forcecast>& pixels,
                          int support, int iterations, std::uint64_t seed, int order, bool colour_correction,
                          bool linear) {
  if (pixels.ndim() != 2 && pixels.ndim() != 3)
    throw py::value_error("the exemplar must have shape (H, W) or (H, W, C)");
  const int height = int(pixels.shape(0)), width = int(pixels.shape(1));
  const int channels = pixels.ndim() == 3 ? int(pixels.shape(2)) : 1;
  const stex::AnalysisParams a = analysis_params(support, iterations, seed, order, colour_correction, linear);
  const float* data = pixels.data();
  py::gil_scoped_release release;
  return stex::Model::analyse(data, width, height, channels, 0, a);
}

stex::Model analyse_file(const std::string& path, int support, int iterations, std::uint64_t seed, int order,
                         bool colour_correction, bool linear) {
  const stex::AnalysisParams a = analysis_params(support, iterations, seed, order, colour_correction, linear);
  py::gil_scoped_release release;
  return stex::Model::analyse(path, a);
}

stex::Model load(const std::string& path) {
  py::gil_scoped_release release;
  return stex::Model::load(path);
}

void save(const stex::Model& model, const std::string& path) {
  py::gil_scoped_release release;
  model.save(path);
}

py::dict info_dict(const stex::Model& model) {
  const stex_model_info i = model.info();
  py::dict d;
  d["kind"] = model.kind();
  d["channels"] = i.channels;
  d["support"] = i.support;
  d["order"] = i.order;
  d["linear"] = bool(i.linear);
  d["exemplar_size"] = py::make_tuple(i.exemplar_width, i.exemplar_height);
  d["iterations"] = i.iterations;
  d["analysis_seed"] = i.analysis_seed;
  d["rme"] = i.rme;
  d["variance_kept"] = i.variance_kept;
  d["mean"] = std::vector<float>(i.mean, i.mean + i.channels);
  return d;
}

}  // namespace

PYBIND11_MODULE(stex, m) {
  m.doc() =
      "stex: texton noise models by example, evaluated on OpenCL devices (libstex's C API, "
      "docs/embedding.md).\n\n"
      "  model = stex.analyse('gravel.png', support=32)\n"
      "  ctx = stex.Context('cpu')\n"
      "  img = ctx.render(model, 0, 0, 256, 256, seed=1)   # float32 (256, 256, C)\n"
      "  vals = ctx.eval_points(model, [[0.5, 0.5], [1e6 + 0.5, 3.5]], seed=1)   # float32 (2, C)";
  m.attr("__version__") = stex::version();

  g_error_type = PyErr_NewExceptionWithDoc(
      "stex.Error", "A failed stex call. Attributes: status (e.g. 'STEX_USAGE'), code (the C status value).",
      PyExc_RuntimeError, nullptr);
  m.add_object("Error", py::handle(g_error_type));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const stex::Error& e) {
      py::object type = py::reinterpret_borrow<py::object>(g_error_type);
      py::object instance = type(e.what());
      instance.attr("status") = e.status_name();
      instance.attr("code") = int(e.status());
      PyErr_SetObject(g_error_type, instance.ptr());
    }
  });

  const stex::RenderParams d;
  const stex::AnalysisParams a;
  const stex::SurfaceParams s;

  py::class_<stex::Model>(m, "Model", "A noise model of any kind (immutable; share it freely between threads).")
      .def("save", &save, py::arg("path"), "Writes the model file atomically.")
      .def_property_readonly("channels", &stex::Model::channels)
      .def_property_readonly("kind", &stex::Model::kind, "'texton', 'lrp', 'gabor', ...")
      .def_property_readonly("support", [](const stex::Model& model) { return model.info().support; })
      .def_property_readonly("info", &info_dict, "The model's properties as a dict.")
      .def("__repr__", [](const stex::Model& model) {
        const stex_model_info i = model.info();
        if (model.kind() != "texton")
          return "<stex.Model " + model.kind() + ", " + std::to_string(i.channels) + " channel(s)>";
        return "<stex.Model " + std::to_string(i.channels) + " channel(s), support " +
               std::to_string(i.support) + ", exemplar " + std::to_string(i.exemplar_width) + "x" +
               std::to_string(i.exemplar_height) + ">";
      });

  py::class_<stex::Context>(
      m, "Context",
      "An OpenCL device context. device: '' (default device), 'cpu', 'gpu', an index or a "
      "name substring.")
      .def(py::init([](const std::string& device) {
             py::gil_scoped_release release;
             return stex::Context(device);
           }),
           py::arg("device") = "")
      .def_property_readonly("device_name", &stex::Context::device_name)
      .def("render", &render, py::arg("model"), py::arg("x"), py::arg("y"), py::arg("width"),
           py::arg("height"), py::kw_only(), py::arg("mni") = d.mni, py::arg("seed") = d.seed,
           py::arg("scale") = d.scale, py::arg("cell_factor") = d.cell_factor, py::arg("strategy") = "auto",
           py::arg("filter") = "auto", py::arg("progress") = py::none(),
           "Renders output pixels [x, x + width) x [y, y + height) into a new float32 array (height, width, "
           "C).\n"
           "filter: 'auto' filters minified views (scale < 1) of texton (order 1), gabor, lrp and cs-rpn models, 'on' "
           "forces it, 'off' point-samples (docs/filtering.md).\n"
           "progress(fraction) is called between chunks of rows; a truthy return value cancels.")
      .def("eval_points", &eval_points, py::arg("model"), py::arg("xy"), py::kw_only(),
           py::arg("mni") = d.mni, py::arg("seed") = d.seed, py::arg("scale") = d.scale,
           py::arg("cell_factor") = d.cell_factor,
           "Evaluates the texture at positions xy of shape (..., 2) (output-pixel coordinates; the centre of "
           "pixel\n"
           "(i, j) is (i + 0.5, j + 0.5) and gives exactly the rendered value). Returns float32 (..., C).")
      .def("eval_surface_points", &eval_surface_points, py::arg("model"), py::arg("positions"),
           py::arg("normals"), py::arg("tangents") = py::none(), py::kw_only(), py::arg("mni") = s.mni,
           py::arg("seed") = s.seed, py::arg("texel") = s.texel, py::arg("cell_factor") = s.cell_factor,
           "Surface noise (S1 section 6) of a texton model at world positions of shape (..., 3) with normals\n"
           "(..., 3) and optional tangents (..., 3) (None: the world X axis projected on the tangent plane).\n"
           "texel = world units per exemplar pixel. Returns float32 (..., C).");

  m.def("analyse", &analyse_file, py::arg("path"), py::kw_only(), py::arg("support") = a.support,
        py::arg("iterations") = a.iterations, py::arg("seed") = a.seed, py::arg("order") = a.order,
        py::arg("colour_correction") = bool(a.colour_correction), py::arg("linear") = bool(a.linear),
        "Analyses an exemplar image file into a texton noise model.");
  m.def("analyse", &analyse_array, py::arg("pixels"), py::kw_only(), py::arg("support") = a.support,
        py::arg("iterations") = a.iterations, py::arg("seed") = a.seed, py::arg("order") = a.order,
        py::arg("colour_correction") = bool(a.colour_correction), py::arg("linear") = bool(a.linear),
        "Analyses an exemplar given as a float array of shape (H, W) or (H, W, C), C in 1..4.");
  m.def("load", &load, py::arg("path"), "Loads a model file (.stex).");
  m.def("save", &save, py::arg("model"), py::arg("path"), "Writes a model file atomically.");
}
