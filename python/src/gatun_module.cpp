// gatun._gatun: the Python bindings (pybind11) of the Gatun library. The Python package (gatun/)
// wraps these functions; arrays cross the boundary without copies where their layout allows.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <tbb/global_control.h>
#include <nlohmann/json.hpp>

#include "codec/pieces.h"
#include "convert/import.h"
#include "format/decode_fields.h"
#include "format/gtn_reader.h"
#include "mesh/box_filter.h"
#include "simplify/levels.h"
#include "validate/info.h"
#include "validate/validator.h"
#include "validate/write_gtn.h"

namespace py = pybind11;
using namespace gtn;

namespace {

// A failed Status, raised in Python as the gatun exception of its category (gatun/_errors.py).
struct StatusError {
  Status status;
};

[[noreturn]] void raise(const Status& st) { throw StatusError{st}; }
template <class T>
T valueOr(StatusOr<T>&& s) {
  if (!s.isOk()) raise(s.status());
  return std::move(s).value();
}
void check(const Status& st) {
  if (!st.isOk()) raise(st);
}

const char* errorClassName(StatusCode code) {
  switch (code) {
    case StatusCode::kInvalidData: return "InvalidDataError";
    case StatusCode::kUnsupported: return "UnsupportedError";
    case StatusCode::kNotOurFile: return "NotOurFileError";
    case StatusCode::kVersionTooNew: return "VersionTooNewError";
    case StatusCode::kUsage: return "UsageError";
    case StatusCode::kIo: return "IoError";
    case StatusCode::kOk: break;
  }
  return "Error";
}

py::dtype dtypeOf(ScalarType t) {
  switch (t) {
    case ScalarType::kInt8: return py::dtype("i1");
    case ScalarType::kUInt8: return py::dtype("u1");
    case ScalarType::kInt16: return py::dtype("<i2");
    case ScalarType::kUInt16: return py::dtype("<u2");
    case ScalarType::kInt32: return py::dtype("<i4");
    case ScalarType::kUInt32: return py::dtype("<u4");
    case ScalarType::kInt64: return py::dtype("<i8");
    case ScalarType::kUInt64: return py::dtype("<u8");
    case ScalarType::kFloat32: return py::dtype("<f4");
    case ScalarType::kFloat64: return py::dtype("<f8");
  }
  return py::dtype("u1");
}

// Hands a vector's buffer to numpy: the vector moves to the heap and a capsule owns it.
template <class V>
py::array handOver(V&& v, const py::dtype& dtype, std::vector<py::ssize_t> shape) {
  using Vec = std::decay_t<V>;
  auto* heap = new Vec(std::forward<V>(v));
  py::capsule owner(heap, [](void* p) { delete static_cast<Vec*>(p); });
  return py::array(dtype, std::move(shape), static_cast<const void*>(heap->data()), owner);
}

py::dict fieldArrays(std::vector<Field>& fields) {
  py::dict d;
  for (Field& f : fields) {
    const py::ssize_t items = static_cast<py::ssize_t>(f.itemCount());
    std::vector<py::ssize_t> shape{items};
    if (f.components != 1) shape.push_back(static_cast<py::ssize_t>(f.components));
    const std::string name = f.name;
    d[py::str(name)] = handOver(std::move(f.bytes), dtypeOf(f.type), std::move(shape));
  }
  return d;
}

// `threads`: the most threads TBB may use while a call runs (tbb::global_control; process-wide, and
// calls that overlap get the smallest of their values). Unset: TBB's default (every core).
struct ThreadLimit {
  explicit ThreadLimit(std::optional<int> threads) {
    if (threads) limit.emplace(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(*threads));
  }
  std::optional<tbb::global_control> limit;
};

void checkThreads(const std::string& what, std::optional<int> threads) {
  if (threads && *threads < 1) raise(usageError(what + ": threads " + std::to_string(*threads) + " must be 1 or more"));
}

py::object jsonToPython(const nlohmann::json& j) {
  // Through Python's json module, so that numbers, nulls and nesting come out as json.loads gives them.
  const std::string text = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  return py::module_::import("json").attr("loads")(text);
}

py::dict readGtn(const std::string& path, std::optional<int64_t> level, std::optional<double> ratio,
                 std::optional<std::vector<std::string>> field_names, std::optional<std::vector<double>> box,
                 std::optional<std::vector<int64_t>> piece_list, std::optional<int> threads) {
  if (level && ratio) raise(usageError(path + ": level and ratio exclude each other"));
  if (piece_list && ratio)
    raise(usageError(path + ": pieces and ratio exclude each other (pieces are those of a stored level)"));
  if (ratio && !(*ratio >= 0 && *ratio <= 1))
    raise(usageError(path + ": ratio " + std::to_string(*ratio) + " is not between 0 and 1"));
  checkThreads(path, threads);
  if (level && *level < 0) raise(usageError(path + ": level " + std::to_string(*level) + " is negative"));
  double lo[3], hi[3];
  if (box) {
    if (box->size() != 6)
      raise(usageError(path + ": box has " + std::to_string(box->size()) +
                       " values, not 6 (xmin, ymin, zmin, xmax, ymax, zmax)"));
    for (int k = 0; k < 3; ++k) {
      lo[k] = (*box)[k];
      hi[k] = (*box)[k + 3];
      if (std::isnan(lo[k]) || std::isnan(hi[k]) || lo[k] > hi[k])
        raise(usageError(path + ": box: its minimum must not exceed its maximum on each axis"));
    }
  }
  TetMeshBuilder builder;
  std::vector<std::string> damage;
  size_t level_read = 0;
  uint64_t merges = 0;
  double level_ratio = 0;
  // A part of a stored level: the pieces decoded and the level's numbers of the mesh's points and
  // tetrahedra (empty: the mesh's indices are the level's).
  std::optional<std::vector<uint32_t>> decoded_pieces;
  std::vector<uint32_t> global_vertex;
  std::vector<uint64_t> global_tet;
  bool part = false;
  {
    py::gil_scoped_release release;
    const ThreadLimit limit(threads);
    GtnOpenOptions oo;
    oo.verify = false;  // random access through the directory; every chunk read is still checksummed
    // As `gtn export`: every chunk's checksum is checked; damage in a chunk this read does not need
    // comes back as a warning, in one it needs as the error.
    auto opened = openGtnChecked(path, oo, [&damage](const std::string& w) { damage.push_back(w); });
    if (!opened.isOk()) {
      // A mesh file given to read: say what reads it.
      const InputFormat in_format = detectInputFormat(path);
      if (in_format != InputFormat::kGtn && in_format != InputFormat::kUnknown)
        raise(usageError(path + ": a " + inputFormatName(in_format) +
                         " file, not .gtn: gatun.read reads .gtn files; convert it with 'gtn convert " + path +
                         " -o FILE.gtn' or read it with meshio"));
    }
    std::unique_ptr<GtnReader> reader = valueOr(std::move(opened));
    GtnReader& r = *reader;
    level_read = static_cast<size_t>(level.value_or(0));
    if (level_read >= r.levels())
      raise(usageError(path + ": level " + std::to_string(level_read) + ": the file holds " +
                       std::to_string(r.levels()) + " level(s), 0 to " + std::to_string(r.levels() - 1)));
    DecodeFields fields;  // every field unless `fields` names some
    if (field_names) fields = valueOr(selectDecodeFields(r.level(level_read).header, *field_names, path, "fields"));
    if (ratio) {
      SimplifyPlan plan;
      const uint64_t target = valueOr(mergesForRatio(r, *ratio));
      check(streamSimplified(r, target, builder, &plan, /*clamp=*/true, &fields));
      level_read = plan.level;
      merges = r.level(plan.level).header.merges + plan.extra_merges;
      // Over the vertices tetrahedra use, as the stored levels' ratios and mergesForRatio count.
      const uint64_t free = valueOr(levelZeroUnreferencedMerges(r)), points = r.level(0).header.points;
      level_ratio = points > free && merges > free ? double(merges - free) / double(points - free) : 0.0;
    } else {
      // The pieces to decode: those named (every piece by default), of them those whose bounding
      // boxes meet the box; the tetrahedra that meet the box are then kept from those (below).
      const std::vector<PieceInfo>& table = r.level(level_read).pieces;
      std::vector<uint32_t> chosen;
      if (piece_list) {
        for (int64_t p : *piece_list)
          if (p < 0 || static_cast<uint64_t>(p) >= table.size())
            raise(usageError(path + ": level " + std::to_string(level_read) + ": pieces: no piece " +
                             std::to_string(p) + " (the level has " + std::to_string(table.size()) +
                             " piece(s), 0 to " + std::to_string(table.size() - 1) + ")"));
        chosen.assign(piece_list->begin(), piece_list->end());
        std::sort(chosen.begin(), chosen.end());
        chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
      } else {
        chosen.resize(table.size());
        for (size_t p = 0; p < table.size(); ++p) chosen[p] = static_cast<uint32_t>(p);
      }
      if (box) {
        const std::vector<uint32_t> in_box = piecesInBox(table, lo, hi);
        std::vector<uint32_t> both;
        std::set_intersection(chosen.begin(), chosen.end(), in_box.begin(), in_box.end(), std::back_inserter(both));
        chosen = std::move(both);
      }
      part = piece_list || box;
      if (chosen.size() == table.size()) {
        check(r.decodeLevel(level_read, builder, nullptr, &fields));
      } else if (chosen.empty()) {
        // Nothing to decode: an empty mesh with the level's (selected) fields.
        const LevelHeader& h = r.level(level_read).header;
        TetMesh& m = builder.mesh();
        m.coord_type = h.coord_type;
        m.metadata = h.metadata;
        for (const FieldDesc& f : h.point_fields) m.point_fields.emplace_back(f.name, f.components, f.type, 0);
        for (const FieldDesc& f : h.cell_fields) m.cell_fields.emplace_back(f.name, f.components, f.type, 0);
      } else {
        DecodedPieces decoded = valueOr(r.decodeLevelPieces(level_read, chosen, &fields));
        builder.mesh() = std::move(decoded.mesh);
        global_vertex = std::move(decoded.global_vertex);
        global_tet = std::move(decoded.global_tet);
      }
      decoded_pieces = std::move(chosen);
      merges = r.level(level_read).header.merges;
      level_ratio = r.level(level_read).ratio;
    }
    if (field_names) dropUndecodedFields(builder.mesh(), fields);
    if (box) {
      std::vector<size_t> kept_points, kept_tets;
      builder.mesh() = cropToBox(builder.mesh(), lo, hi, &kept_points, &kept_tets);
      if (part) {
        // The level's numbers of the kept points and tetrahedra.
        std::vector<uint32_t> gv(kept_points.size());
        for (size_t i = 0; i < kept_points.size(); ++i)
          gv[i] = global_vertex.empty() ? static_cast<uint32_t>(kept_points[i]) : global_vertex[kept_points[i]];
        std::vector<uint64_t> gt(kept_tets.size());
        for (size_t i = 0; i < kept_tets.size(); ++i)
          gt[i] = global_tet.empty() ? kept_tets[i] : global_tet[kept_tets[i]];
        global_vertex = std::move(gv);
        global_tet = std::move(gt);
      }
    }
    if (part && global_vertex.empty() && builder.mesh().numPoints() > 0) {
      // Every piece decoded: the indices are the level's numbers.
      global_vertex.resize(builder.mesh().numPoints());
      for (size_t i = 0; i < global_vertex.size(); ++i) global_vertex[i] = static_cast<uint32_t>(i);
    }
    if (part && global_tet.empty() && builder.mesh().numTets() > 0) {
      global_tet.resize(builder.mesh().numTets());
      for (size_t i = 0; i < global_tet.size(); ++i) global_tet[i] = i;
    }
  }
  TetMesh& mesh = builder.mesh();
  py::dict out;
  const py::ssize_t n = static_cast<py::ssize_t>(mesh.numPoints());
  if (mesh.coord_type == ScalarType::kFloat32) {
    // The decoder holds coordinates as doubles: float32 ones are narrowed (exactly) to their stored type.
    std::vector<float> narrow(mesh.coords.begin(), mesh.coords.end());
    out["points"] = handOver(std::move(narrow), dtypeOf(ScalarType::kFloat32), {n, 3});
  } else {
    out["points"] = handOver(std::move(mesh.coords), dtypeOf(ScalarType::kFloat64), {n, 3});
  }
  const py::ssize_t m = static_cast<py::ssize_t>(mesh.numTets());
  out["tets"] = handOver(std::move(mesh.tets), dtypeOf(ScalarType::kUInt32), {m, 4});
  out["point_data"] = fieldArrays(mesh.point_fields);
  out["cell_data"] = fieldArrays(mesh.cell_fields);
  py::dict meta;
  for (const auto& [k, v] : mesh.metadata) meta[py::str(k)] = py::str(v);
  out["metadata"] = meta;
  out["level"] = level_read;
  out["merges"] = merges;
  out["ratio"] = level_ratio;
  out["warnings"] = damage;
  if (part) {
    out["point_ids"] = handOver(std::move(global_vertex), dtypeOf(ScalarType::kUInt32), {n});
    out["tet_ids"] = handOver(std::move(global_tet), dtypeOf(ScalarType::kUInt64), {m});
  } else {
    out["point_ids"] = py::none();
    out["tet_ids"] = py::none();
  }
  if (decoded_pieces) out["pieces"] = *decoded_pieces;
  else out["pieces"] = py::none();
  return out;
}

// The library's decode of a stored level into a mesh in memory, as `gtn export` does before it
// writes (bench/python compares gatun.read with it): no Python objects, only the counts come back.
py::tuple decodeOnly(const std::string& path, size_t level) {
  TetMeshBuilder builder;
  {
    py::gil_scoped_release release;
    GtnOpenOptions oo;
    oo.verify = false;
    std::unique_ptr<GtnReader> reader = valueOr(openGtnChecked(path, oo, nullptr));
    if (level >= reader->levels()) raise(usageError(path + ": level " + std::to_string(level) + " does not exist"));
    check(reader->decodeLevel(level, builder));
  }
  return py::make_tuple(builder.mesh().numPoints(), builder.mesh().numTets());
}

ScalarType scalarTypeOf(const py::array& a, const std::string& what) {
  const py::dtype dt = a.dtype();
  const char kind = dt.kind();
  const py::ssize_t size = dt.itemsize();
  if (kind == 'f' && size == 4) return ScalarType::kFloat32;
  if (kind == 'f' && size == 8) return ScalarType::kFloat64;
  if (kind == 'i' || kind == 'u') {
    const bool u = kind == 'u';
    switch (size) {
      case 1: return u ? ScalarType::kUInt8 : ScalarType::kInt8;
      case 2: return u ? ScalarType::kUInt16 : ScalarType::kInt16;
      case 4: return u ? ScalarType::kUInt32 : ScalarType::kInt32;
      case 8: return u ? ScalarType::kUInt64 : ScalarType::kInt64;
    }
  }
  raise(usageError(what + ": dtype " + py::str(static_cast<py::object>(dt)).cast<std::string>() +
                   " is not one of int8..uint64, float32, float64"));
}

// Fields from a dict of arrays of `items` rows each (1-D: one component; 2-D: a column per component).
std::vector<Field> fieldsFrom(const py::dict& data, size_t items, const std::string& what) {
  std::vector<Field> out;
  for (auto [key, value] : data) {
    const std::string name = py::str(key).cast<std::string>();
    py::array a = py::array::ensure(value, py::array::c_style);
    if (!a) raise(usageError(what + " '" + name + "': not an array"));
    const ScalarType type = scalarTypeOf(a, what + " '" + name + "'");
    if (a.ndim() < 1 || a.ndim() > 2 || static_cast<size_t>(a.shape(0)) != items || (a.ndim() == 2 && a.shape(1) < 1))
      raise(usageError(what + " '" + name + "': shape must be (" + std::to_string(items) + ",) or (" +
                       std::to_string(items) + ", components)"));
    if (a.dtype().byteorder() == '>') raise(usageError(what + " '" + name + "': big-endian arrays are not supported"));
    const uint32_t comps = a.ndim() == 2 ? static_cast<uint32_t>(a.shape(1)) : 1;
    Field f(name, comps, type, items);
    std::memcpy(f.bytes.data(), a.data(), f.bytes.size());
    out.push_back(std::move(f));
  }
  return out;
}

py::list writeGtn(const std::string& path, py::array points, py::array tets, py::dict point_data, py::dict cell_data,
                  py::dict metadata, int levels, bool merge_tree, double level_storage, bool verify,
                  const std::string& simplify_field, double w_density, double w_geometry, bool greedy_ranking,
                  bool keep_invalid, std::optional<int> threads) {
  const std::string source = "gatun.write(" + path + ")";
  checkThreads(source, threads);
  TetMesh mesh;
  {
    py::array p = py::array::ensure(points, py::array::c_style);
    if (!p || p.ndim() != 2 || p.shape(1) != 3) raise(usageError(source + ": points must be an (n, 3) array"));
    const ScalarType ct = scalarTypeOf(p, source + ": points");
    if (!isFloatType(ct)) raise(usageError(source + ": points must be float32 or float64"));
    mesh.coord_type = ct;
    const size_t n = static_cast<size_t>(p.shape(0));
    mesh.coords.resize(3 * n);
    if (ct == ScalarType::kFloat32) {
      const float* src = static_cast<const float*>(p.data());
      for (size_t i = 0; i < 3 * n; ++i) mesh.coords[i] = src[i];
    } else {
      std::memcpy(mesh.coords.data(), p.data(), 3 * n * sizeof(double));
    }
  }
  {
    py::array_t<int64_t, py::array::c_style | py::array::forcecast> t(tets);
    if (t.ndim() != 2 || t.shape(1) != 4) raise(usageError(source + ": tets must be an (m, 4) array"));
    const size_t m = static_cast<size_t>(t.shape(0));
    mesh.tets.resize(m);
    const int64_t* src = t.data();
    const int64_t n = static_cast<int64_t>(mesh.numPoints());
    for (size_t i = 0; i < m; ++i)
      for (int k = 0; k < 4; ++k) {
        const int64_t v = src[4 * i + k];
        if (v < 0 || v >= n)
          raise(usageError(source + ": tetrahedron " + std::to_string(i) + " refers to point " + std::to_string(v) +
                           " (the mesh has " + std::to_string(n) + " points)"));
        mesh.tets[i][k] = static_cast<uint32_t>(v);
      }
  }
  mesh.point_fields = fieldsFrom(point_data, mesh.numPoints(), source + ": point field");
  mesh.cell_fields = fieldsFrom(cell_data, mesh.numTets(), source + ": cell field");
  for (auto [k, v] : metadata) mesh.setMetadata(py::str(k).cast<std::string>(), py::str(v).cast<std::string>());
  std::vector<std::string> warnings;
  {
    py::gil_scoped_release release;
    const ThreadLimit limit(threads);
    check(mesh.checkConsistency(source));
    // What an importer does last (orientation by exact predicates), as `gtn convert` has it done.
    ImportResult imported{std::move(mesh), {}};
    finishImport(imported);
    if (imported.report.flipped)
      warnings.push_back(source + ": flipped " + std::to_string(imported.report.flipped) +
                         " tetrahedra to positive orientation");
    if (imported.report.zero_volume)
      warnings.push_back(source + ": " + std::to_string(imported.report.zero_volume) +
                         " tetrahedra have zero volume (kept)");
    for (const std::string& w : imported.report.warnings) warnings.push_back(source + ": " + w);
    GtnConvertOptions o;
    o.levels = levels;
    o.merge_tree = merge_tree;
    o.level_storage = level_storage;
    o.keep_invalid = keep_invalid;
    o.ranking.field = simplify_field;
    o.ranking.w_density = w_density;
    o.ranking.w_geometry = w_geometry;
    if (greedy_ranking) {
      o.ranking.lazy = false;
      o.ranking.parts = 1;
    }
    GtnWriteOptions wo;
    wo.tool_version = GTN_VERSION_STRING;
    wo.command_line = source;
    wo.verify = verify;
    check(writeGtnWithLevels(path, imported.mesh, o, wo, source, &warnings));
  }
  py::list out;
  for (const std::string& w : warnings) out.append(w);
  return out;
}

py::object info(const std::vector<std::string>& inputs, bool merge_tree) {
  nlohmann::json j;
  {
    py::gil_scoped_release release;
    j = valueOr(infoJson(inputs, ImportOptions{}, merge_tree));
  }
  return jsonToPython(j);
}

py::tuple validate(const std::string& path, std::vector<std::string> against, bool quick, size_t max_issues) {
  ValidateOptions options;
  options.quick = quick;
  options.max_issues = max_issues;
  options.against = std::move(against);
  if (quick && !options.against.empty()) raise(usageError("validate: quick and against exclude each other"));
  nlohmann::json j;
  bool errors = false;
  {
    py::gil_scoped_release release;
    const InputFormat format = detectInputFormat(path);
    const bool gtn = format == InputFormat::kGtn || format == InputFormat::kUnknown;
    ValidationReport report = valueOr(gtn ? validateGtnFile(path, options) : validateMeshFiles({path}, options));
    j = report.toJson(path);
    errors = report.hasErrors();
  }
  return py::make_tuple(jsonToPython(j), errors);
}

py::object mergeTree(const std::string& path) {
  nlohmann::json j;
  {
    py::gil_scoped_release release;
    std::unique_ptr<GtnReader> reader = valueOr(GtnReader::open(path));
    std::optional<MergeTreeReport> rep = valueOr(mergeTreeReport(*reader));
    j = rep ? mergeTreeReportJson(*rep) : nlohmann::json(nullptr);
  }
  return jsonToPython(j);
}

}  // namespace

PYBIND11_MODULE(_gatun, m) {
  m.doc() = "Bindings of the Gatun library (use the gatun package, not this module)";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const StatusError& e) {
      py::object cls = py::module_::import("gatun._errors").attr(errorClassName(e.status.code()));
      PyErr_SetObject(cls.ptr(), py::str(e.status.message()).ptr());
    }
  });
  m.attr("__version__") = GTN_VERSION_STRING;
  m.def("read", &readGtn, py::arg("path"), py::arg("level") = py::none(), py::arg("ratio") = py::none(),
        py::arg("fields") = py::none(), py::arg("box") = py::none(), py::arg("pieces") = py::none(),
        py::arg("threads") = py::none());
  m.def("decode", &decodeOnly, py::arg("path"), py::arg("level") = 0);
  m.def("write", &writeGtn, py::arg("path"), py::arg("points"), py::arg("tets"), py::arg("point_data"),
        py::arg("cell_data"), py::arg("metadata"), py::arg("levels"), py::arg("merge_tree"), py::arg("level_storage"),
        py::arg("verify"), py::arg("simplify_field"), py::arg("w_density"), py::arg("w_geometry"),
        py::arg("greedy_ranking"), py::arg("keep_invalid"), py::arg("threads") = py::none());
  m.def("info", &info, py::arg("inputs"), py::arg("merge_tree"));
  m.def("validate", &validate, py::arg("path"), py::arg("against"), py::arg("quick"), py::arg("max_issues"));
  m.def("merge_tree", &mergeTree, py::arg("path"));
}
