// pybind11 bindings: osteon._core. Thin: converts NumPy arrays to engine views and results back
// to NumPy without copying, releases the GIL while the engine works. The public API is
// python/osteon.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <array>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <vector>

#include "osteon/analysis.hpp"
#include "osteon/correction.hpp"
#include "osteon/decimate.hpp"
#include "osteon/notch.hpp"
#include "osteon/progress.hpp"
#include "osteon/readers.hpp"
#include "osteon/section.hpp"
#include "osteon/skinning.hpp"
#include "osteon/slicer.hpp"

namespace py = pybind11;
using namespace osteon;

namespace {

using DoubleArray = py::array_t<double, py::array::c_style | py::array::forcecast>;
using Int32Array = py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>;
using Int64Array = py::array_t<std::int64_t, py::array::c_style | py::array::forcecast>;

// Hands a vector's buffer to NumPy (no copy); the capsule frees it with the array.
template <class T>
py::array_t<T> to_numpy(std::vector<T>&& v) {
  auto* owned = new std::vector<T>(std::move(v));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<T>*>(p); });
  return py::array_t<T>({static_cast<py::ssize_t>(owned->size())}, {sizeof(T)}, owned->data(),
                        free_when_done);
}

py::array_t<double> to_numpy(std::vector<Vec3>&& v) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be packed");
  auto* owned = new std::vector<Vec3>(std::move(v));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<Vec3>*>(p); });
  return py::array_t<double>({static_cast<py::ssize_t>(owned->size()), py::ssize_t(3)},
                             {3 * sizeof(double), sizeof(double)},
                             reinterpret_cast<double*>(owned->data()), free_when_done);
}

py::array_t<double> to_numpy_rows3(std::vector<double>&& v) {
  auto* owned = new std::vector<double>(std::move(v));
  py::capsule free_when_done(owned, [](void* p) { delete static_cast<std::vector<double>*>(p); });
  return py::array_t<double>({static_cast<py::ssize_t>(owned->size() / 3), py::ssize_t(3)},
                             {3 * sizeof(double), sizeof(double)}, owned->data(), free_when_done);
}

py::array_t<bool> to_bool(const std::vector<std::uint8_t>& v) {
  py::array_t<bool> out(static_cast<py::ssize_t>(v.size()));
  auto m = out.mutable_unchecked<1>();
  for (std::size_t i = 0; i < v.size(); ++i) m(i) = v[i] != 0;
  return out;
}

void require_rows3(const py::array& a, const char* name) {
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw std::invalid_argument(std::string(name) + " must have shape (N, 3)");
}

Skeleton make_skeleton(const DoubleArray& heads, const DoubleArray& tails,
                       const Int32Array& parents, const std::vector<std::string>& names) {
  require_rows3(heads, "heads");
  require_rows3(tails, "tails");
  if (parents.ndim() != 1) throw std::invalid_argument("parents must be a 1D array");
  const py::ssize_t nb = heads.shape(0);
  if (tails.shape(0) != nb || parents.shape(0) != nb)
    throw std::invalid_argument("heads, tails and parents must have the same number of bones");
  Skeleton s;
  s.heads.resize(nb);
  s.tails.resize(nb);
  s.parents.resize(nb);
  auto h = heads.unchecked<2>();
  auto t = tails.unchecked<2>();
  auto p = parents.unchecked<1>();
  for (py::ssize_t b = 0; b < nb; ++b) {
    s.heads[b] = Vec3(h(b, 0), h(b, 1), h(b, 2));
    s.tails[b] = Vec3(t(b, 0), t(b, 1), t(b, 2));
    s.parents[b] = p(b);
  }
  s.names = names;
  return s;
}

// CSR triplets (indptr, indices, data) of a (V, B) sparse weight matrix, shape-checked. With
// `narrow`, 32-bit bone indices (SciPy's usual type) are kept as they are in `indices32`.
struct CsrArrays {
  Int64Array indptr, indices;
  Int32Array indices32;
  DoubleArray data;
  bool narrow = false;
};

CsrArrays csr_arrays(const py::object& csr, Index num_vertices, bool allow_narrow = false) {
  auto parts = csr.cast<py::tuple>();
  CsrArrays c;
  c.indptr = parts[0].cast<Int64Array>();
  c.data = parts[2].cast<DoubleArray>();
  c.narrow = allow_narrow && py::isinstance<py::array_t<std::int32_t>>(parts[1]);
  py::ssize_t nnz = 0;
  if (c.narrow) {
    c.indices32 = parts[1].cast<Int32Array>();
    nnz = c.indices32.ndim() == 1 ? c.indices32.shape(0) : -1;
  } else {
    c.indices = parts[1].cast<Int64Array>();
    nnz = c.indices.ndim() == 1 ? c.indices.shape(0) : -1;
  }
  if (c.indptr.ndim() != 1 || c.indptr.shape(0) != num_vertices + 1)
    throw std::invalid_argument("weights must have one row per vertex (" +
                                std::to_string(num_vertices) + ")");
  if (c.data.ndim() != 1 || nnz != c.data.shape(0) || c.indptr.at(num_vertices) != nnz)
    throw std::invalid_argument("weights: sparse indices and data do not match");
  return c;
}

// Weights arrive as None, a dense (V, B) array, or CSR triplets (indptr, indices, data).
std::unique_ptr<BoneWeights> make_weights(const py::object& dense, const py::object& csr,
                                          Index num_vertices, int num_bones) {
  if (!dense.is_none()) {
    DoubleArray w = dense.cast<DoubleArray>();
    if (w.ndim() != 2 || w.shape(0) != num_vertices || w.shape(1) != num_bones)
      throw std::invalid_argument("weights must have shape (V, B) = (" +
                                  std::to_string(num_vertices) + ", " + std::to_string(num_bones) +
                                  ")");
    return std::make_unique<BoneWeights>(
        BoneWeights::from_dense(w.data(), num_vertices, num_bones));
  }
  if (!csr.is_none()) {
    const CsrArrays c = csr_arrays(csr, num_vertices);
    return std::make_unique<BoneWeights>(BoneWeights::from_csr(
        c.indptr.data(), c.indices.data(), c.data.data(), num_vertices, num_bones));
  }
  return nullptr;
}

// The regions whose thickness an analysis deferred (AnalysisOptions::defer_thickness).
struct PendingThickness {
  std::vector<std::shared_ptr<const SectionPolygon>> regions;  // S, null: computed already
};

// One result field to Python (OSTEON_RESULT_FIELDS' types): arrays without a copy, flags as
// bool, scalars as numbers, lists of index arrays as lists.
template <class T>
py::object to_python(std::vector<T>&& v) {
  return to_numpy(std::move(v));
}
py::object to_python(std::vector<std::uint8_t>&& v) { return to_bool(v); }
py::object to_python(std::vector<std::vector<std::int32_t>>&& pieces) {
  py::list out;
  for (auto& piece : pieces) out.append(to_numpy(std::move(piece)));
  return out;
}
py::object to_python(double x) { return py::float_(x); }
py::object to_python(int x) { return py::int_(x); }

// Every row of OSTEON_RESULT_FIELDS by its name, plus the deferred thickness handle.
py::dict result_to_dict(AnalysisResult&& r) {
  py::dict d;
  if (r.thickness_pending.empty()) {
    d["thickness_pending"] = py::none();
  } else {
    d["thickness_pending"] = py::cast(PendingThickness{std::move(r.thickness_pending)});
  }
#define OSTEON_TO_DICT(type, name, init, shape, unit, doc) d[#name] = to_python(std::move(r.name));
  OSTEON_RESULT_FIELDS(OSTEON_TO_DICT)
#undef OSTEON_TO_DICT
  return d;
}

// (name, shape, dtype, unit, doc) of every result field, in the table's order; dtype is the
// NumPy dtype of the array ("float64", "bool", ...), or "float" / "int" / "list".
py::list result_fields() {
  py::list out;
  auto dtype = [](const py::object& empty) -> std::string {
    if (py::isinstance<py::array>(empty)) return py::str(empty.attr("dtype"));
    return py::str(empty.attr("__class__").attr("__name__"));
  };
#define OSTEON_FIELD_ROW(type, name, init, shape, unit, doc) \
  out.append(py::make_tuple(#name, shape, dtype(to_python(type init)), unit, doc));
  OSTEON_RESULT_FIELDS(OSTEON_FIELD_ROW)
#undef OSTEON_FIELD_ROW
  return out;
}

// Reusable analyzer holding faces and weights (live mode re-runs with new vertices / pose).
class PyAnalyzer {
 public:
  PyAnalyzer(const Int32Array& faces, Index num_vertices, int num_bones, const py::object& dense,
             const py::object& csr, const AnalysisOptions& options) {
    require_rows3(faces, "faces");
    const int threads = options.threads;
    if (dense.is_none() && !csr.is_none()) {
      // Sparse weights: the analysis needs only each vertex's dominant bone; no copy of them.
      const CsrArrays c = csr_arrays(csr, num_vertices, /*allow_narrow=*/true);
      std::vector<int> dominant =
          c.narrow ? dominant_bones_csr(c.indptr.data(), c.indices32.data(), c.data.data(),
                                        num_vertices, num_bones, threads)
                   : dominant_bones_csr(c.indptr.data(), c.indices.data(), c.data.data(),
                                        num_vertices, num_bones, threads);
      analyzer_ = std::make_unique<Analyzer>(faces.data(), faces.shape(0), num_vertices,
                                             std::move(dominant), num_bones, options);
    } else {
      auto weights = make_weights(dense, csr, num_vertices, num_bones);
      analyzer_ = std::make_unique<Analyzer>(faces.data(), faces.shape(0), num_vertices,
                                             weights.get(), num_bones, options);
    }
    num_vertices_ = num_vertices;
  }
  py::dict run(const DoubleArray& vertices, const Skeleton& s, Progress* progress,
               bool keep_for_next_run) {
    require_rows3(vertices, "vertices");
    if (vertices.shape(0) != num_vertices_)
      throw std::invalid_argument("vertices has " + std::to_string(vertices.shape(0)) +
                                  " rows but the analyzer was built for " +
                                  std::to_string(num_vertices_));
    AnalysisResult r;
    {
      py::gil_scoped_release release;
      // One analyzer keeps per-run state: concurrent calls on the same object take turns.
      std::lock_guard<std::mutex> lock(mutex_);
      r = analyzer_->run(vertices.data(), s, progress, keep_for_next_run);
    }
    return result_to_dict(std::move(r));
  }

 private:
  std::unique_ptr<Analyzer> analyzer_;
  Index num_vertices_ = 0;
  std::mutex mutex_;
};

}  // namespace

// The bytes of a Python bytes object, without a copy (valid while the object lives).
static std::string_view bytes_view(const py::bytes& b) {
  char* data = nullptr;
  Py_ssize_t size = 0;
  PyBytes_AsStringAndSize(b.ptr(), &data, &size);
  return {data, static_cast<std::size_t>(size)};
}

template <class T>
py::array_t<T> to_array(const std::vector<T>& v) {
  return py::array_t<T>(static_cast<py::ssize_t>(v.size()), v.data());
}

PYBIND11_MODULE(_core, m) {
  m.doc() = "osteon engine (C++): skeleton-sectional structural analysis; mm, N, MPa";
  // A cancelled run (Progress.cancel()) raises osteon._core.Cancelled, not a ValueError.
  py::register_exception<Cancelled>(m, "Cancelled");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const std::invalid_argument& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    }
  });

  py::class_<Skeleton>(m, "Skeleton",
                       "A bone skeleton, checked once when made (engine form of osteon.Skeleton).")
      .def(py::init([](const DoubleArray& heads, const DoubleArray& tails,
                       const Int32Array& parents, const std::vector<std::string>& names) {
             Skeleton s = make_skeleton(heads, tails, parents, names);
             validate_skeleton(s);
             return s;
           }),
           py::arg("heads"), py::arg("tails"), py::arg("parents"), py::arg("names"),
           "heads, tails (B,3) mm, parents (B,) int (-1 = root), names (B); ValueError naming "
           "the problem (cycle, zero-length bone, ...).")
      .def_property_readonly("num_bones", &Skeleton::num_bones, "Number of bones B.");

  py::class_<Progress>(m, "Progress",
                       "Progress and cancel switch of a run, shared with the engine's threads.")
      .def(py::init<>())
      .def_property_readonly(
          "sections_done", [](const Progress& p) { return p.sections_done.load(); },
          "sections of the current analysis whose cut is done")
      .def_property_readonly(
          "sections_total", [](const Progress& p) { return p.sections_total.load(); },
          "sections the current analysis plans (0 until planned)")
      .def_property_readonly(
          "runs_done", [](const Progress& p) { return p.runs_done.load(); },
          "analyses finished (a correction runs several)")
      .def_property_readonly("cancelled", &Progress::cancelled, "True once cancel() was called")
      .def("cancel", &Progress::cancel, "Ask the run to stop (any thread); it raises Cancelled")
      .def("reset", &Progress::reset, "Clear the counters and the cancel switch");

  m.def("result_fields", &result_fields,
        "(name, shape, dtype, unit, doc) of every field of an analysis result "
        "(cpp/include/osteon/result_fields.hpp), in order.");

  m.def(
      "parse_obj",
      [](const py::bytes& text) {
        const std::string_view view = bytes_view(text);
        readers::ObjData d;
        {
          py::gil_scoped_release release;
          d = readers::parse_obj(view);
        }
        return py::make_tuple(to_array(d.vertices), to_array(d.corners), to_array(d.counts),
                              d.error, d.unsupported);
      },
      "OBJ bytes -> (xyz (3V,), corners (0-based), corners per face, error, unsupported)");
  m.def(
      "parse_numbers",
      [](const py::bytes& text) {
        const std::string_view view = bytes_view(text);
        std::vector<double> out;
        std::size_t bad = 0;
        {
          py::gil_scoped_release release;
          bad = readers::parse_numbers(view, out);
        }
        return py::make_tuple(to_array(out), bad == std::string_view::npos
                                                 ? py::ssize_t(-1)
                                                 : static_cast<py::ssize_t>(bad));
      },
      "whitespace-separated numbers -> (values, offset of the first non-number or -1)");
  m.def(
      "count_sections",
      [](const Skeleton& s, double interval) { return count_sections(s, interval); },
      py::arg("skeleton"), py::arg("interval"),
      "Exact number of sections an analysis plans at interval (mm), before any cut.");

  py::class_<PendingThickness>(m, "_PendingThickness",
                               "Regions whose thickness an analysis left for later (mm).")
      .def(
          "fill",
          [](const PendingThickness& p, const DoubleArray& thickness) {
            std::vector<double> out(thickness.data(), thickness.data() + thickness.size());
            if (p.regions.size() > out.size())
              throw py::value_error("thickness array shorter than the sections");
            {
              py::gil_scoped_release release;
              fill_section_thickness(p.regions, out);
            }
            return to_numpy(std::move(out));
          },
          py::arg("thickness"),
          "A copy of `thickness` (S,) mm with every deferred section's thickness filled in.");

  py::class_<AnalysisOptions>(m, "AnalysisOptions", "Settings of one analysis (N, MPa, mm).")
      .def(py::init<>())
      .def_readwrite("force", &AnalysisOptions::force, "N")
      .def_readwrite("allowable_stress", &AnalysisOptions::allowable_stress, "MPa")
      .def_readwrite("interval", &AnalysisOptions::interval, "mm")
      .def_readwrite("held_bone", &AnalysisOptions::held_bone, "bone index; -1 = main root")
      .def_readwrite("gap_tolerance", &AnalysisOptions::gap_tolerance, "mm; < 0: 1 % of size")
      .def_readwrite("threads", &AnalysisOptions::threads, "0 = all cores")
      .def_readwrite("local_cuts", &AnalysisOptions::local_cuts)
      .def_readwrite("reuse_sections", &AnalysisOptions::reuse_sections)
      .def_readwrite("keep_outlines", &AnalysisOptions::keep_outlines)
      .def_readwrite("defer_thickness", &AnalysisOptions::defer_thickness)
      .def_readwrite("junctions", &AnalysisOptions::junctions)
      .def_readwrite("min_thickness", &AnalysisOptions::min_thickness,
                     "mm; thinner sections are flagged too_thin (0 = no check)")
      .def_readwrite("notch_sensitivity", &AnalysisOptions::notch_sensitivity,
                     "q, 0..1: governing stress = (1 + q (Kt - 1)) x nominal")
      .def_readwrite("min_notch_radius", &AnalysisOptions::min_notch_radius,
                     "mm; corners sharper than this are taken at this radius")
      .def_property(
          "build_direction",
          [](const AnalysisOptions& o) {
            return std::array<double, 3>{o.build_direction.x(), o.build_direction.y(),
                                         o.build_direction.z()};
          },
          [](AnalysisOptions& o, const std::array<double, 3>& d) {
            o.build_direction = Vec3(d[0], d[1], d[2]);
          },
          "FDM build direction (3,), model frame")
      .def_readwrite("layer_strength_ratio", &AnalysisOptions::layer_strength_ratio,
                     "layer / in-plane strength (1 = isotropic)")
      // The printed section (osteon/printed_section.hpp), set from a PrintProfile by
      // osteon.printed.engine_print_options.
      .def_property(
          "print_kind", [](const AnalysisOptions& o) { return o.print.kind; },
          [](AnalysisOptions& o, int k) { o.print.kind = k; },
          "0 solid, 1 FDM (walls, skins, infill), 2 hollow shell (resin)")
      .def_property(
          "print_wall_depth", [](const AnalysisOptions& o) { return o.print.wall_depth; },
          [](AnalysisOptions& o, double v) { o.print.wall_depth = v; },
          "mm: FDM perimeters' depth in the layer plane, or the resin shell")
      .def_property(
          "print_skin_depth", [](const AnalysisOptions& o) { return o.print.skin_depth; },
          [](AnalysisOptions& o, double v) { o.print.skin_depth = v; },
          "mm: solid top/bottom skins along the build direction")
      .def_property(
          "print_infill_build", [](const AnalysisOptions& o) { return o.print.infill_build; },
          [](AnalysisOptions& o, double v) { o.print.infill_build = v; },
          "infill stiffness fraction for stress along the build direction")
      .def_property(
          "print_infill_layer", [](const AnalysisOptions& o) { return o.print.infill_layer; },
          [](AnalysisOptions& o, double v) { o.print.infill_layer = v; },
          "infill stiffness fraction for stress in the layer plane")
      .def_property(
          "print_solid_infill_below_area",
          [](const AnalysisOptions& o) { return o.print.solid_infill_below_area; },
          [](AnalysisOptions& o, double v) { o.print.solid_infill_below_area = v; },
          "mm^2: a layer's infill island under this area is filled solid")
      .def_property(
          "print_skin_max_slope", [](const AnalysisOptions& o) { return o.print.skin_max_slope; },
          [](AnalysisOptions& o, double v) { o.print.skin_max_slope = v; },
          "radians from the layer plane: skins only under surfaces this flat (pi/2: all)")
      .def_property(
          "print_layer_height", [](const AnalysisOptions& o) { return o.print.layer_height; },
          [](AnalysisOptions& o, double v) { o.print.layer_height = v; },
          "mm: FDM layer height (the rows of the skin widening)")
      .def_property(
          "print_skin_growth", [](const AnalysisOptions& o) { return o.print.skin_growth; },
          [](AnalysisOptions& o, double v) { o.print.skin_growth = v; },
          "mm: a skin strip narrower than twice this is widened by it into the infill (0: off)");

  py::class_<CorrectionOptions>(m, "CorrectionOptions", "Limits of the correction loop.")
      .def(py::init<>())
      .def_readwrite("max_scale", &CorrectionOptions::max_scale)
      .def_readwrite("max_rounds", &CorrectionOptions::max_rounds)
      .def_readwrite("target_ratio", &CorrectionOptions::target_ratio)
      .def_readwrite("thin_direction", &CorrectionOptions::thin_direction)
      .def_readwrite("flat_aspect", &CorrectionOptions::flat_aspect)
      .def_property(
          "bone_x_axes",
          [](const CorrectionOptions& o) { return to_numpy(std::vector<Vec3>(o.bone_x_axes)); },
          [](CorrectionOptions& o, const py::object& axes) {
            o.bone_x_axes.clear();
            if (axes.is_none()) return;
            const DoubleArray a = axes.cast<DoubleArray>();
            require_rows3(a, "bone_x_axes");
            auto u = a.unchecked<2>();
            for (py::ssize_t b = 0; b < a.shape(0); ++b)
              o.bone_x_axes.emplace_back(u(b, 0), u(b, 1), u(b, 2));
          },
          "(B,3) local x axes of the bones, or empty")
      .def_property(
          "bone_long_axes",
          [](const CorrectionOptions& o) { return to_numpy(std::vector<Vec3>(o.bone_long_axes)); },
          [](CorrectionOptions& o, const py::object& axes) {
            o.bone_long_axes.clear();
            if (axes.is_none()) return;
            const DoubleArray a = axes.cast<DoubleArray>();
            require_rows3(a, "bone_long_axes");
            auto u = a.unchecked<2>();
            for (py::ssize_t b = 0; b < a.shape(0); ++b)
              o.bone_long_axes.emplace_back(u(b, 0), u(b, 1), u(b, 2));
          },
          "(B,3) axes the bones scale across (scale 1 along them), or empty: the segments");

  py::class_<PyAnalyzer>(m, "Analyzer", "Reusable analysis of one mesh topology.")
      .def(py::init<const Int32Array&, Index, int, const py::object&, const py::object&,
                    const AnalysisOptions&>(),
           py::arg("faces"), py::arg("num_vertices"), py::arg("num_bones"), py::arg("dense"),
           py::arg("csr"), py::arg("options"))
      .def("run", &PyAnalyzer::run, py::arg("vertices"), py::arg("skeleton"),
           py::arg("progress") = nullptr, py::arg("keep_for_next_run") = true,
           "Analyse vertices (V,3 mm) with a posed Skeleton; progress: a Progress or None; "
           "keep_for_next_run=False: a one-off run that keeps no inputs for a partial re-run.");

  m.def(
      "correct",
      [](const DoubleArray& vertices, const Int32Array& faces, const Skeleton& s,
         const py::object& dense, const py::object& csr, const AnalysisOptions& o,
         const CorrectionOptions& co, Progress* progress) {
        require_rows3(vertices, "vertices");
        require_rows3(faces, "faces");
        auto weights = make_weights(dense, csr, vertices.shape(0), s.num_bones());
        if (!weights) throw std::invalid_argument("correct() needs skinning weights");
        const MeshView mesh{vertices.data(), vertices.shape(0), faces.data(), faces.shape(0)};
        CorrectionResult r;
        {
          py::gil_scoped_release release;
          r = correct(mesh, s, *weights, o, co, progress);
        }
        py::dict d;
        d["bone_scale"] = to_numpy(std::move(r.bone_scale));
        d["bone_scale_x"] = to_numpy(std::move(r.bone_scale_x));
        d["bone_scale_z"] = to_numpy(std::move(r.bone_scale_z));
        d["bone_x_axis"] = to_numpy(std::move(r.bone_x_axis));
        d["vertices"] = to_numpy_rows3(std::move(r.vertices));
        py::list rounds;
        for (const auto& rd : r.rounds)
          rounds.append(py::make_tuple(rd.bone, rd.factor, rd.max_stress_after, rd.axis));
        d["rounds"] = rounds;
        d["converged"] = r.converged;
        d["reason"] = r.reason;
        d["unfixed_sections"] = r.unfixed_sections;
        d["max_displacement"] = r.max_displacement;
        d["volume_change_percent"] = r.volume_change_percent;
        d["before"] = result_to_dict(std::move(r.before));
        d["after"] = result_to_dict(std::move(r.after));
        return d;
      },
      py::arg("vertices"), py::arg("faces"), py::arg("skeleton"), py::arg("dense"), py::arg("csr"),
      py::arg("options"), py::arg("correction_options"), py::arg("progress") = nullptr,
      "Correction loop (paper §5); see osteon.correct.");

  m.def(
      "skin",
      [](const DoubleArray& vertices, const Skeleton& s, const py::object& dense,
         const py::object& csr, const std::vector<double>& bone_scale,
         const py::object& bone_scale_z, const py::object& bone_x_axes,
         const py::object& bone_long_axes) {
        require_rows3(vertices, "vertices");
        auto weights = make_weights(dense, csr, vertices.shape(0), s.num_bones());
        if (!weights) throw std::invalid_argument("skin() needs skinning weights");
        validate_weights(*weights, vertices.shape(0), s.num_bones());
        if (bone_scale.size() != static_cast<std::size_t>(s.num_bones()))
          throw std::invalid_argument("bone_scale must have one entry per bone");
        AxisScales scales{
            bone_scale, bone_scale, std::vector<Vec3>(s.num_bones(), Vec3::Zero()), {}};
        if (!bone_scale_z.is_none()) scales.z = bone_scale_z.cast<std::vector<double>>();
        if (!bone_x_axes.is_none()) {
          const DoubleArray axes = bone_x_axes.cast<DoubleArray>();
          require_rows3(axes, "bone_x_axes");
          if (axes.shape(0) != s.num_bones())
            throw std::invalid_argument("bone_x_axes must have one row per bone");
          auto a = axes.unchecked<2>();
          for (py::ssize_t b = 0; b < axes.shape(0); ++b)
            scales.x_axis[b] = Vec3(a(b, 0), a(b, 1), a(b, 2));
        }
        if (!bone_long_axes.is_none()) {
          const DoubleArray axes = bone_long_axes.cast<DoubleArray>();
          require_rows3(axes, "bone_long_axes");
          if (axes.shape(0) != s.num_bones())
            throw std::invalid_argument("bone_long_axes must have one row per bone");
          auto a = axes.unchecked<2>();
          for (py::ssize_t b = 0; b < axes.shape(0); ++b)
            scales.long_axis.emplace_back(a(b, 0), a(b, 1), a(b, 2));
        }
        std::vector<double> out(vertices.size());
        {
          py::gil_scoped_release release;
          skin_axis_scales(vertices.data(), vertices.shape(0), s, *weights, scales, out.data());
        }
        return to_numpy_rows3(std::move(out));
      },
      py::arg("vertices"), py::arg("skeleton"), py::arg("dense"), py::arg("csr"),
      py::arg("bone_scale"), py::arg("bone_scale_z") = py::none(),
      py::arg("bone_x_axes") = py::none(), py::arg("bone_long_axes") = py::none(),
      "Linear blend skinning with per-bone cross-section scales (x, optionally z and x axes).");

  m.def(
      "section_properties",
      [](const DoubleArray& outer, const std::vector<DoubleArray>& holes) {
        auto to_loop = [](const DoubleArray& a) {
          if (a.ndim() != 2 || a.shape(1) != 2)
            throw std::invalid_argument("a loop must have shape (N, 2)");
          std::vector<Vec2> loop(a.shape(0));
          auto u = a.unchecked<2>();
          for (py::ssize_t i = 0; i < a.shape(0); ++i) loop[i] = Vec2(u(i, 0), u(i, 1));
          return loop;
        };
        SectionPolygon poly;
        poly.outer = to_loop(outer);
        for (const auto& h : holes) poly.holes.push_back(to_loop(h));
        const SectionProperties p = section_properties(poly);
        py::dict d;
        d["area"] = p.area;
        d["centroid"] = py::make_tuple(p.centroid.x(), p.centroid.y());
        d["second_moment"] =
            py::make_tuple(p.second_moment(0, 0), p.second_moment(0, 1), p.second_moment(1, 1));
        d["modulus"] = p.modulus;
        d["valid"] = p.valid;
        return d;
      },
      py::arg("outer"), py::arg("holes"),
      "Exact area (mm^2), centroid, second moments (mm^4) and min section modulus (mm^3).");

  m.def(
      "slice_section",
      [](const DoubleArray& vertices, const Int32Array& faces, const std::vector<double>& origin,
         const std::vector<double>& normal, double gap_tolerance) {
        require_rows3(vertices, "vertices");
        require_rows3(faces, "faces");
        if (origin.size() != 3 || normal.size() != 3)
          throw std::invalid_argument("origin and normal must have 3 components");
        const MeshView mesh{vertices.data(), vertices.shape(0), faces.data(), faces.shape(0)};
        validate_mesh(mesh);
        const PlaneFrame frame = PlaneFrame::make(Vec3(origin[0], origin[1], origin[2]),
                                                  Vec3(normal[0], normal[1], normal[2]));
        const SectionGeometry g = slice_section(mesh, frame, gap_tolerance);
        auto loop3 = [&](const std::vector<Vec2>& loop) {
          std::vector<Vec3> pts;
          for (const Vec2& q : loop) pts.push_back(frame.to_world(q));
          return to_numpy(std::move(pts));
        };
        py::dict d;
        d["found"] = g.found;
        d["flags"] = g.flags;
        d["outer"] = loop3(g.polygon.outer);
        py::list holes;
        for (const auto& h : g.polygon.holes) holes.append(loop3(h));
        d["holes"] = holes;
        return d;
      },
      py::arg("vertices"), py::arg("faces"), py::arg("origin"), py::arg("normal"),
      py::arg("gap_tolerance"),
      "The section region of one plane around its origin (3D loops, mm).");

  m.def(
      "decimate_mesh",
      [](const DoubleArray& vertices, const Int32Array& faces, Index target_faces) {
        require_rows3(vertices, "vertices");
        require_rows3(faces, "faces");
        const MeshView mesh{vertices.data(), vertices.shape(0), faces.data(), faces.shape(0)};
        DecimatedMesh out;
        {
          py::gil_scoped_release release;
          out = decimate_mesh(mesh, target_faces);
        }
        const auto nf = static_cast<py::ssize_t>(out.faces.size() / 3);
        py::array_t<std::int32_t> f({nf, py::ssize_t(3)});
        std::copy(out.faces.begin(), out.faces.end(), f.mutable_data());
        return py::make_tuple(to_numpy_rows3(std::move(out.vertices)), f);
      },
      py::arg("vertices"), py::arg("faces"), py::arg("target_faces"),
      "Quadric edge-collapse decimation to at most target_faces faces, keeping a closed "
      "manifold closed and manifold: (vertices (V',3) mm, faces (F',3) int32).");

  m.attr("FLAG_GAP_CLOSED") = static_cast<int>(kFlagGapClosed);
  m.attr("FLAG_OPEN") = static_cast<int>(kFlagOpen);
  m.attr("FLAG_OUTSIDE") = static_cast<int>(kFlagOutside);
  m.attr("FLAG_HOLLOW") = static_cast<int>(kFlagHollow);
  m.attr("FLAG_EMPTY") = static_cast<int>(kFlagEmpty);
  m.attr("FLAG_DEGENERATE") = static_cast<int>(kFlagDegenerate);
  m.attr("FLAG_NON_MANIFOLD") = static_cast<int>(kFlagNonManifold);
  m.attr("FLAG_UNRELIABLE") = static_cast<int>(kFlagUnreliable);
  m.attr("FLAG_TOO_THIN") = static_cast<int>(kFlagTooThin);
  m.attr("FLAG_JUNCTION") = static_cast<int>(kFlagJunction);
  m.attr("FLAG_NOTCH") = static_cast<int>(kFlagNotch);
  m.def("shoulder_fillet_kt", &shoulder_fillet_kt, py::arg("big_diameter"),
        py::arg("small_diameter"), py::arg("radius"),
        "Kt of a stepped round bar's shoulder fillet in bending (D, d, r in mm; the larger of "
        "Roark Table 17.1 / Peterson Chart 3.11, clamped on the safe side outside its range, and "
        "Tipton, Sorem & Rolovic 1996's FEM fit; docs/notch.md)");
}
