// Exodus II importer (.exo, .e, .ex2, .exii, .gen), read with the SEACAS Exodus library (Debian's
// libexodusii), which reads both of its netCDF containers: the classic one ("CDF\x01", "\x02",
// "\x05") and netCDF-4 (HDF5).
//
// What becomes of a file: every node is a point (coordinates in the file's word size: float32 files
// stay float32); the element blocks of volume elements (TETRA, HEX, WEDGE, PYRAMID and their
// higher-order forms, whose corners come first and are kept; the other nodes stay as points that no
// tetrahedron uses) are split into tetrahedra as the VTK importers split their cells
// (cell_split.h: Exodus numbers the corners of these four as VTK does), and so are NFACED blocks
// (polyhedra, each a list of faces of the file's face blocks, NSIDED or of one face type), as VTK
// polyhedra whose faces the split winds alike. The cell field "block_id"
// holds each element's block id. Of one time step (ImportOptions::exodus_time_step, the last one by
// default), the nodal variables become point fields and the element variables cell fields, in the
// file's word size; variables named NAMEX, NAMEY, NAMEZ (or NAMEx, NAMEy, NAMEz) one after the other
// become one 3-component field NAME, as VTK's Exodus reader and meshio join them (velocity_x,
// velocity_y, velocity_z: "velocity_"). An element variable
// that a block does not define (the truth table) is NaN there, and so is a variable whose values the
// library does not find (a warning), except nodal variables stored as meshio stores them
// (netcdfNodal). Global variables of the step become
// metadata ("exodus.global.NAME"). What is not read is said in a warning each: blocks of lower
// dimension (triangles, quadrilaterals, shells, bars, NSIDED polygons, ...), node sets, side sets and
// the other sets, edge blocks and face blocks (but as NFACED elements' faces), element attributes
// and the variables of sets.
#include <dlfcn.h>
#include <exodusII.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <type_traits>

#include "convert/cell_split.h"
#include "convert/import.h"
#include "convert/vtk_common.h"
#include "format/file_io.h"

namespace gtn {

namespace {

// The Exodus library, loaded when the first Exodus file is read: linked in, it would load MPI (Debian
// builds it on the MPI flavour of netCDF and HDF5) into every gtn process, which then takes about
// 80 ms more to start. Null, with the reason in *why, when it cannot be loaded.
struct ExodusApi {
  decltype(&::ex_close) ex_close = nullptr;
  decltype(&::ex_get_block_param) ex_get_block_param = nullptr;
  decltype(&::ex_get_conn) ex_get_conn = nullptr;
  decltype(&::ex_get_coord) ex_get_coord = nullptr;
  decltype(&::ex_get_entity_count_per_polyhedra) ex_get_entity_count_per_polyhedra = nullptr;
  decltype(&::ex_get_err) ex_get_err = nullptr;
  decltype(&::ex_get_ids) ex_get_ids = nullptr;
  decltype(&::ex_get_init_ext) ex_get_init_ext = nullptr;
  decltype(&::ex_get_time) ex_get_time = nullptr;
  decltype(&::ex_get_truth_table) ex_get_truth_table = nullptr;
  decltype(&::ex_get_var) ex_get_var = nullptr;
  decltype(&::ex_get_variable_names) ex_get_variable_names = nullptr;
  decltype(&::ex_get_variable_param) ex_get_variable_param = nullptr;
  decltype(&::ex_inquire_int) ex_inquire_int = nullptr;
  decltype(&::ex_opts) ex_opts = nullptr;
  decltype(&::ex_set_max_name_length) ex_set_max_name_length = nullptr;
  decltype(&::ex_set_int64_status) ex_set_int64_status = nullptr;
  decltype(&::ex_open_int) ex_open_int = nullptr;
  // Of the netCDF library the Exodus library loads (optional): error texts, and nodal variables that
  // the Exodus library does not find (netcdfNodal).
  const char* (*nc_strerror)(int) = nullptr;
  int (*nc_inq_varid)(int, const char*, int*) = nullptr;
  int (*nc_inq_varndims)(int, int, int*) = nullptr;
  int (*nc_inq_vardimid)(int, int, int*) = nullptr;
  int (*nc_inq_dimlen)(int, int, size_t*) = nullptr;
  int (*nc_get_vara_double)(int, int, const size_t*, const size_t*, double*) = nullptr;
};
const ExodusApi* exodusApi(std::string* why) {
  static std::string error;
  static const ExodusApi* api = [&]() -> const ExodusApi* {
    void* lib = nullptr;
    // The library's name at run time, then the one the build found.
    for (const char* name : {"libexoIIv2c.so.5", GTN_EXODUS_LIBRARY}) {
      lib = dlopen(name, RTLD_NOW | RTLD_LOCAL);
      if (lib) break;
      error = dlerror();
    }
    if (!lib) return nullptr;
    static ExodusApi api;
    bool ok = true;
    auto load = [&](auto& f, const char* name) {
      f = reinterpret_cast<std::remove_reference_t<decltype(f)>>(dlsym(lib, name));
      if (!f && ok) ok = false, error = std::string("the library has no ") + name;
    };
    load(api.ex_close, "ex_close");
    load(api.ex_get_block_param, "ex_get_block_param");
    load(api.ex_get_conn, "ex_get_conn");
    load(api.ex_get_coord, "ex_get_coord");
    load(api.ex_get_entity_count_per_polyhedra, "ex_get_entity_count_per_polyhedra");
    load(api.ex_get_err, "ex_get_err");
    load(api.ex_get_ids, "ex_get_ids");
    load(api.ex_get_init_ext, "ex_get_init_ext");
    load(api.ex_get_time, "ex_get_time");
    load(api.ex_get_truth_table, "ex_get_truth_table");
    load(api.ex_get_var, "ex_get_var");
    load(api.ex_get_variable_names, "ex_get_variable_names");
    load(api.ex_get_variable_param, "ex_get_variable_param");
    load(api.ex_inquire_int, "ex_inquire_int");
    load(api.ex_opts, "ex_opts");
    load(api.ex_set_max_name_length, "ex_set_max_name_length");
    load(api.ex_set_int64_status, "ex_set_int64_status");
    load(api.ex_open_int, "ex_open_int");
    api.nc_strerror = reinterpret_cast<const char* (*)(int)>(dlsym(lib, "nc_strerror"));
    auto optional = [&](auto& f, const char* name) {
      f = reinterpret_cast<std::remove_reference_t<decltype(f)>>(dlsym(lib, name));
    };
    optional(api.nc_inq_varid, "nc_inq_varid");
    optional(api.nc_inq_varndims, "nc_inq_varndims");
    optional(api.nc_inq_vardimid, "nc_inq_vardimid");
    optional(api.nc_inq_dimlen, "nc_inq_dimlen");
    optional(api.nc_get_vara_double, "nc_get_vara_double");
    return ok ? &api : nullptr;
  }();
  if (!api) *why = error;
  return api;
}

// The Exodus library's last error, as netCDF states it where it has a netCDF code.
std::string exodusError(const ExodusApi& api) {
  const char* msg = nullptr;
  const char* func = nullptr;
  int code = 0;
  api.ex_get_err(&msg, &func, &code);
  std::string s = msg && *msg ? msg : "";
  if (code > 0 || code < -1) {
    // Negative codes are netCDF's.
    const char* nc = code < 0 && api.nc_strerror ? api.nc_strerror(code) : nullptr;
    if (nc && s.find(nc) == std::string::npos) s += std::string(s.empty() ? "" : " (") + nc + (s.empty() ? "" : ")");
  }
  return s.empty() ? "the Exodus library gave no reason" : s;
}

// Closes the file on every way out.
struct ExodusFile {
  const ExodusApi& api;
  int id = -1;
  ~ExodusFile() {
    if (id >= 0) api.ex_close(id);
  }
};

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string trimmed(const char* s) {
  std::string out(s);
  while (!out.empty() && std::isspace(static_cast<unsigned char>(out.back()))) out.pop_back();
  size_t b = 0;
  while (b < out.size() && std::isspace(static_cast<unsigned char>(out[b]))) ++b;
  return out.substr(b);
}

// A volume element type: the VTK cell type with the same corner order and the number of corners.
struct VolumeType {
  int vtk_type = 0;
  int corners = 0;
};
// The element types (Exodus names them by a word, often with the node count after it: TETRA4,
// TET10, HEX27, WEDGE15, PYRAMID13) that hold volume; false for the others.
bool volumeType(const std::string& type, VolumeType* out) {
  const std::string t = upper(type);
  auto starts = [&](const char* p) { return t.rfind(p, 0) == 0; };
  if (starts("TET")) *out = {kVtkTetra, 4};
  else if (starts("HEX")) *out = {kVtkHexahedron, 8};
  else if (starts("WEDGE")) *out = {kVtkWedge, 6};
  else if (starts("PYRA")) *out = {kVtkPyramid, 5};
  else return false;
  return true;
}

// The faces of the file's face blocks, which NFACED elements (polyhedra) list by number: face f
// (numbered from 1 across the blocks, in the order of their ids) has the nodes
// nodes[offsets[f - 1] .. offsets[f]) (numbered from 0). A face block is NSIDED (each face's node
// count stored) or of one face type (TRI3, QUAD4, ...: its nodes per face).
struct FaceTable {
  std::vector<int64_t> offsets{0};
  std::vector<int64_t> nodes;
  size_t size() const { return offsets.size() - 1; }
};

// `fits` checks a count the file announces against its size (importExodus).
template <class Fits>
StatusOr<FaceTable> readFaceBlocks(const ExodusApi& api, const std::string& path, int exoid, int64_t num_face_blk,
                                   int64_t num_nodes, const Fits& fits) {
  FaceTable table;
  GTN_RETURN_IF_ERROR(fits(num_face_blk, 1, "face blocks"));
  if (num_face_blk > INT32_MAX)
    return unsupported(path + ": " + std::to_string(num_face_blk) + " face blocks; at most 2^31-1 are supported");
  std::vector<int64_t> ids(static_cast<size_t>(num_face_blk));
  if (num_face_blk > 0 && api.ex_get_ids(exoid, EX_FACE_BLOCK, ids.data()) < 0)
    return invalidData(path + ": cannot read the face block ids (ex_get_ids: " + exodusError(api) + ")");
  std::vector<int> counts;
  std::vector<int64_t> conn;
  for (const int64_t id : ids) {
    ex_block param{};
    param.id = id;
    param.type = EX_FACE_BLOCK;
    const std::string where = "face block " + std::to_string(id);
    if (api.ex_get_block_param(exoid, &param) < 0)
      return invalidData(path + ": cannot read " + where + " (ex_get_block_param: " + exodusError(api) + ")");
    param.topology[MAX_STR_LENGTH] = '\0';
    const bool nsided = upper(trimmed(param.topology)).rfind("NSIDED", 0) == 0;
    const int64_t faces = param.num_entry, per = param.num_nodes_per_entry;
    if (faces < 0 || per < 0) return invalidData(path + ": " + where + " has a negative count");
    if (faces == 0) continue;
    GTN_RETURN_IF_ERROR(fits(faces, 4, where + " faces"));
    // An NSIDED block's node count is its total; another's, each face's.
    GTN_RETURN_IF_ERROR(fits(per, 4, where + " nodes per face"));
    const int64_t total = nsided ? per : faces * per;
    GTN_RETURN_IF_ERROR(fits(total, 4, where + " face nodes"));
    if (!nsided && per < 3)
      return invalidData(path + ": " + where + " (" + trimmed(param.topology) + ") has " + std::to_string(per) +
                         " nodes per face; a face has at least 3");
    conn.assign(static_cast<size_t>(total), 0);
    if (total > 0 && api.ex_get_conn(exoid, EX_FACE_BLOCK, id, conn.data(), nullptr, nullptr) < 0)
      return invalidData(path + ": cannot read the nodes of " + where + " (ex_get_conn: " + exodusError(api) + ")");
    counts.assign(static_cast<size_t>(faces), static_cast<int>(std::min<int64_t>(per, INT32_MAX)));
    if (nsided && api.ex_get_entity_count_per_polyhedra(exoid, EX_FACE_BLOCK, id, counts.data()) < 0)
      return invalidData(path + ": cannot read the node counts of " + where +
                         " (ex_get_entity_count_per_polyhedra: " + exodusError(api) + ")");
    int64_t at = 0;
    for (int64_t f = 0; f < faces; ++f) {
      const int n = counts[static_cast<size_t>(f)];
      if (n < 3 || n > total - at)
        return invalidData(path + ": " + where + ", face " + std::to_string(f + 1) + " has " + std::to_string(n) +
                           " nodes (at least 3, within the block's " + std::to_string(total) + ")");
      for (int i = 0; i < n; ++i, ++at) {
        const int64_t v = conn[static_cast<size_t>(at)];
        if (v < 1 || v > num_nodes)
          return invalidData(path + ": " + where + ", face " + std::to_string(f + 1) + " refers to node " +
                             std::to_string(v) + "; nodes are numbered 1 to " + std::to_string(num_nodes));
        table.nodes.push_back(v - 1);
      }
      table.offsets.push_back(static_cast<int64_t>(table.nodes.size()));
    }
    if (at != total)
      return invalidData(path + ": " + where + ": its faces' node counts add up to " + std::to_string(at) + ", not " +
                         std::to_string(total));
  }
  return table;
}

// Reads `names` (count names of `type`) with the database's name length.
StatusOr<std::vector<std::string>> readNames(const ExodusApi& api, const std::string& path, int exoid,
                                             ex_entity_type type, int count, size_t name_length, const char* what) {
  std::vector<std::vector<char>> buffers(static_cast<size_t>(count), std::vector<char>(name_length + 1, '\0'));
  std::vector<char*> pointers;
  for (auto& b : buffers) pointers.push_back(b.data());
  if (count > 0 && api.ex_get_variable_names(exoid, type, count, pointers.data()) < 0)
    return invalidData(path + ": cannot read the names of the " + what + ": " + exodusError(api));
  std::vector<std::string> names;
  for (auto& b : buffers) {
    b.back() = '\0';
    names.push_back(trimmed(b.data()));
    if (names.back().empty()) names.back() = std::string(what) + "_" + std::to_string(names.size());
  }
  return names;
}

// Groups of variables that become one field: their indices (0-based) and the field's name. Three
// names one after the other that differ only in a last letter x, y, z (the same case, after a common
// stem) are one 3-component field named after the stem; a variable of several components stands alone.
struct VariableGroup {
  std::string name;
  std::vector<int> variables;
};
std::vector<VariableGroup> groupVariables(const std::vector<std::string>& names,
                                          const std::vector<size_t>& components = {}) {
  std::vector<VariableGroup> groups;
  auto single = [&](size_t i) { return components.empty() || components[i] == 1; };
  for (size_t i = 0; i < names.size();) {
    if (i + 2 < names.size() && single(i) && single(i + 1) && single(i + 2)) {
      const std::string& a = names[i];
      const std::string& b = names[i + 1];
      const std::string& c = names[i + 2];
      const size_t n = a.size();
      if (n >= 2 && b.size() == n && c.size() == n && a.compare(0, n - 1, b, 0, n - 1) == 0 &&
          a.compare(0, n - 1, c, 0, n - 1) == 0 &&
          ((a.back() == 'x' && b.back() == 'y' && c.back() == 'z') ||
           (a.back() == 'X' && b.back() == 'Y' && c.back() == 'Z'))) {
        groups.push_back({a.substr(0, n - 1), {static_cast<int>(i), static_cast<int>(i + 1), static_cast<int>(i + 2)}});
        i += 3;
        continue;
      }
    }
    groups.push_back({names[i], {static_cast<int>(i)}});
    ++i;
  }
  return groups;
}

void putValue(Field& f, size_t item, uint32_t c, double v) {
  if (f.type == ScalarType::kFloat32) f.set<float>(item, c, static_cast<float>(v));
  else f.set<double>(item, c, v);
}

// A nodal variable as netCDF stores it in its own variable vals_nod_var<k> (k 1-based): dimensions
// (time_step, num_nodes), the layout of Exodus's "large model", or (time_step, num_nodes, C) for C
// components. meshio writes every file so, vectors as the second form, without the file_size attribute
// that tells the Exodus library to look there: the library then finds no values (a warning, not an
// error). Its components, 0 where the variable is not so stored or netCDF cannot be asked.
struct NetcdfNodal {
  int varid = -1;
  size_t components = 0;
};
NetcdfNodal netcdfNodal(const ExodusApi& api, int exoid, int k, size_t num_nodes) {
  NetcdfNodal out;
  if (!api.nc_inq_varid || !api.nc_inq_varndims || !api.nc_inq_vardimid || !api.nc_inq_dimlen ||
      !api.nc_get_vara_double)
    return out;
  int varid = -1, ndims = 0;
  const std::string name = "vals_nod_var" + std::to_string(k);
  if (api.nc_inq_varid(exoid, name.c_str(), &varid) != 0 || api.nc_inq_varndims(exoid, varid, &ndims) != 0 ||
      (ndims != 2 && ndims != 3))
    return out;
  int dims[3];
  size_t lengths[3] = {0, 0, 1};
  if (api.nc_inq_vardimid(exoid, varid, dims) != 0) return out;
  for (int d = 0; d < ndims; ++d)
    if (api.nc_inq_dimlen(exoid, dims[d], &lengths[d]) != 0) return out;
  if (lengths[1] != num_nodes || lengths[2] < 1 || lengths[2] > 64) return out;
  out.varid = varid;
  out.components = lengths[2];
  return out;
}
// Reads step (1-based) of such a variable: num_nodes x components values, component fastest.
bool readNetcdfNodal(const ExodusApi& api, int exoid, const NetcdfNodal& v, int step, size_t num_nodes,
                     std::vector<double>* values) {
  values->assign(num_nodes * v.components, 0.0);
  const size_t start[3] = {static_cast<size_t>(step - 1), 0, 0};
  const size_t count[3] = {1, num_nodes, v.components};
  return num_nodes == 0 || api.nc_get_vara_double(exoid, v.varid, start, count, values->data()) == 0;
}

std::string plural(int64_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// The classic netCDF format (CDF-1, CDF-2 and CDF-5, "The NetCDF Classic Format Specification")
// reads past the end of a truncated file as zeros, without an error. Its header says where every
// variable's values lie: this returns the end of the last of them (the whole file a complete copy
// has), or an error where the header itself is cut short or malformed.
class ClassicHeader {
 public:
  ClassicHeader(const std::string& path, std::string_view bytes) : path_(path), b_(bytes) {}

  StatusOr<uint64_t> dataEnd() {
    if (b_.size() < 4) return fail("the netCDF header is cut short");
    version_ = static_cast<uint8_t>(b_[3]);
    pos_ = 4;
    GTN_ASSIGN_OR_RETURN(uint64_t numrecs, size(version_ == 5 ? 8 : 4));
    const bool streaming = numrecs == (version_ == 5 ? UINT64_MAX : UINT32_MAX);
    // Dimensions.
    std::vector<uint64_t> dims;
    GTN_ASSIGN_OR_RETURN(const uint64_t ndims, listHeader(0x0A, "dimension"));
    for (uint64_t i = 0; i < ndims; ++i) {
      GTN_RETURN_IF_ERROR(name());
      GTN_ASSIGN_OR_RETURN(const uint64_t length, count());
      dims.push_back(length);
    }
    GTN_RETURN_IF_ERROR(attributes());
    // Variables: name, dimension ids, attributes, type, vsize, begin.
    GTN_ASSIGN_OR_RETURN(const uint64_t nvars, listHeader(0x0B, "variable"));
    struct Var {
      uint64_t values_per_record, type_size, begin;
      bool record;
    };
    std::vector<Var> vars;
    uint64_t record_size = 0;
    for (uint64_t v = 0; v < nvars; ++v) {
      GTN_RETURN_IF_ERROR(name());
      GTN_ASSIGN_OR_RETURN(const uint64_t rank, count());
      if (rank > 1024) return fail("a variable of rank " + std::to_string(rank));
      Var var{1, 0, 0, false};
      for (uint64_t d = 0; d < rank; ++d) {
        GTN_ASSIGN_OR_RETURN(const uint64_t id, count());
        if (id >= dims.size())
          return fail("a variable names dimension " + std::to_string(id) + " of " + std::to_string(dims.size()));
        if (d == 0 && dims[id] == 0) {
          var.record = true;
          continue;
        }
        if (dims[id] != 0 && var.values_per_record > UINT64_MAX / dims[id]) return fail("a variable too large");
        var.values_per_record *= dims[id];
      }
      GTN_RETURN_IF_ERROR(attributes());
      GTN_ASSIGN_OR_RETURN(const uint64_t type, size(4));
      var.type_size = typeSize(type);
      if (var.type_size == 0) return fail("unknown netCDF type " + std::to_string(type));
      GTN_ASSIGN_OR_RETURN(const uint64_t vsize, size(version_ == 5 ? 8 : 4));
      GTN_ASSIGN_OR_RETURN(var.begin, size(version_ == 1 ? 4 : 8));
      if (var.record) {
        if (vsize > UINT64_MAX - record_size) return fail("records too large");
        record_size += vsize;
      }
      vars.push_back(var);
    }
    const auto record_vars = std::count_if(vars.begin(), vars.end(), [](const Var& x) { return x.record; });
    uint64_t end = pos_;
    for (const Var& var : vars) {
      if (var.values_per_record > UINT64_MAX / var.type_size) return fail("a variable too large");
      const uint64_t bytes = var.values_per_record * var.type_size;
      uint64_t e = var.begin;
      if (var.record && !streaming) {
        if (numrecs == 0) continue;
        // Records hold every record variable's vsize; one record variable alone is not padded.
        const uint64_t step = record_vars == 1 ? bytes : record_size;
        if (e > UINT64_MAX - bytes || numrecs - 1 > (UINT64_MAX - e - bytes) / std::max<uint64_t>(step, 1))
          return fail("records too large");
        e += (numrecs - 1) * step;
      } else if (var.record) {
        continue;
      }
      if (e > UINT64_MAX - bytes) return fail("a variable too large");
      end = std::max(end, e + bytes);
    }
    return end;
  }

 private:
  Status fail(const std::string& why) const {
    return invalidData(path_ + ": netCDF header, byte offset " + std::to_string(pos_) + ": " + why);
  }
  StatusOr<uint64_t> size(size_t n) {
    if (b_.size() - pos_ < n) return fail("the header is cut short");
    uint64_t v = 0;
    for (size_t i = 0; i < n; ++i) v = v << 8 | static_cast<uint8_t>(b_[pos_ + i]);
    pos_ += n;
    return v;
  }
  StatusOr<uint64_t> count() { return size(version_ == 5 ? 8 : 4); }
  Status skip(uint64_t n) {
    const uint64_t padded = n + (4 - n % 4) % 4;
    if (n > b_.size() || b_.size() - pos_ < padded) return fail("the header is cut short");
    pos_ += padded;
    return Status::ok();
  }
  Status name() {
    GTN_ASSIGN_OR_RETURN(const uint64_t n, count());
    return skip(n);
  }
  // A list's tag and element count (ABSENT: both zero).
  StatusOr<uint64_t> listHeader(uint32_t tag, const char* what) {
    GTN_ASSIGN_OR_RETURN(const uint64_t t, size(4));
    GTN_ASSIGN_OR_RETURN(const uint64_t n, count());
    if (t == 0 && n == 0) return uint64_t{0};
    if (t != tag) return fail(std::string("expected the ") + what + " list");
    if (n > b_.size()) return fail(std::string("a ") + what + " count beyond the file");
    return n;
  }
  Status attributes() {
    GTN_ASSIGN_OR_RETURN(const uint64_t n, listHeader(0x0C, "attribute"));
    for (uint64_t i = 0; i < n; ++i) {
      GTN_RETURN_IF_ERROR(name());
      GTN_ASSIGN_OR_RETURN(const uint64_t type, size(4));
      GTN_ASSIGN_OR_RETURN(const uint64_t values, count());
      const uint64_t ts = typeSize(type);
      if (ts == 0) return fail("unknown netCDF type " + std::to_string(type));
      if (values > b_.size() / ts) return fail("an attribute beyond the file");
      GTN_RETURN_IF_ERROR(skip(values * ts));
    }
    return Status::ok();
  }
  uint64_t typeSize(uint64_t type) const {
    switch (type) {
      case 1:
      case 2:
      case 7: return 1;  // byte, char, ubyte
      case 3:
      case 8: return 2;  // short, ushort
      case 4:
      case 5:
      case 9: return 4;  // int, float, uint
      case 6:
      case 10:
      case 11: return 8;  // double, int64, uint64
      default: return 0;
    }
  }

  const std::string& path_;
  std::string_view b_;
  uint8_t version_ = 1;
  uint64_t pos_ = 0;
};

// The end of a netCDF-4 (HDF5) file as its superblock records it (base address plus end-of-file
// address, little-endian, of the superblock's offset size), or 0 where it cannot be told. A file cut
// short ends before it; the libraries would only say "HDF error" (and the Exodus library that netCDF-4 is
// not supported).
uint64_t hdf5End(std::string_view b) {
  if (b.size() < 12 || b.compare(0, 8, "\x89HDF\r\n\x1a\n") != 0) return 0;
  const uint8_t version = static_cast<uint8_t>(b[8]);
  const size_t offsets = static_cast<uint8_t>(version <= 1 ? (b.size() > 13 ? b[13] : 0) : b[9]);
  if (offsets != 2 && offsets != 4 && offsets != 8) return 0;
  const size_t first = version == 0 ? 24 : version == 1 ? 28 : version <= 3 ? 12 : 0;
  if (first == 0 || b.size() < first + 3 * offsets) return 0;
  auto address = [&](size_t at) {
    uint64_t v = 0;
    for (size_t i = 0; i < offsets; ++i) v |= static_cast<uint64_t>(static_cast<uint8_t>(b[at + i])) << (8 * i);
    return v;
  };
  const uint64_t undefined = offsets == 8 ? UINT64_MAX : (uint64_t{1} << (8 * offsets)) - 1;
  const uint64_t base = address(first);
  const uint64_t eof = address(first + 2 * offsets);  // after the base and the free-space or extension address
  if (base == undefined || eof == undefined || eof > UINT64_MAX - base) return 0;
  return base + eof;
}

struct Block {
  int64_t id = 0;
  std::string type;
  int64_t elements = 0;
  int64_t nodes_per_element = 0;
  int64_t attributes = 0;
  bool volume = false;
  VolumeType vt;
  size_t first_cell = 0;  // of the volume blocks: the index of its first element among the volume cells
};

}  // namespace

StatusOr<ImportResult> importExodus(const std::string& path, const ImportOptions& options) {
  std::string why;
  const ExodusApi* loaded = exodusApi(&why);
  if (!loaded)
    return unsupported(path +
                       ": an Exodus II file, but the Exodus library (libexoIIv2c, Debian's libexodusii5) "
                       "cannot be loaded: " +
                       why);
  const ExodusApi& api = *loaded;
  struct stat sb;
  if (::stat(path.c_str(), &sb) != 0) return ioError(path + ": cannot read it");
  const uint64_t file_size = static_cast<uint64_t>(sb.st_size);
  // A classic file must hold all that its header describes (netCDF would read the missing bytes as
  // zeros), and a netCDF-4 file the end of file its HDF5 superblock records.
  // The header lies at the start: the first 256 MiB hold any real one.
  std::string bytes(static_cast<size_t>(std::min<uint64_t>(file_size, uint64_t{256} << 20)), '\0');
  if (std::FILE* f = std::fopen(path.c_str(), "rb")) {
    bytes.resize(std::fread(bytes.data(), 1, bytes.size(), f));
    std::fclose(f);
  }
  const bool classic = bytes.size() >= 4 && bytes.compare(0, 3, "CDF") == 0;
  if (classic) {
    ClassicHeader header(path, bytes);
    GTN_ASSIGN_OR_RETURN(const uint64_t end, header.dataEnd());
    bytes = std::string();
    if (end > file_size)
      return invalidData(path + ": truncated: its netCDF header places values up to byte " + std::to_string(end) +
                         ", but the file has " + std::to_string(file_size) + " bytes");
  }
  if (const uint64_t end = hdf5End(bytes); end > file_size)
    return invalidData(path + ": truncated: its HDF5 superblock gives the file " + std::to_string(end) +
                       " bytes, but it has " + std::to_string(file_size));
  // The library would print its errors and, by default in some versions, abort: it is told to do
  // neither, and its messages go into ours.
  api.ex_opts(EX_DEFAULT);
  int comp_ws = 8, io_ws = 0;
  float version = 0;
  ExodusFile file{api};
  file.id = api.ex_open_int(path.c_str(), EX_READ, &comp_ws, &io_ws, &version, EX_API_VERS_NODOT);
  if (file.id < 0)
    return invalidData(path + ": cannot open it as an Exodus II file (ex_open: " + exodusError(api) + ")");
  const int exoid = file.id;
  api.ex_set_int64_status(exoid, EX_ALL_INT64_API);
  const int64_t used_name_length = api.ex_inquire_int(exoid, EX_INQ_DB_MAX_USED_NAME_LENGTH);
  const size_t name_length = static_cast<size_t>(std::clamp<int64_t>(used_name_length, MAX_STR_LENGTH, 255));
  api.ex_set_max_name_length(exoid, static_cast<int>(name_length));

  ex_init_params init{};
  if (api.ex_get_init_ext(exoid, &init) < 0)
    return invalidData(path + ": cannot read the Exodus header (ex_get_init_ext: " + exodusError(api) + ")");
  if (init.num_dim != 3)
    return unsupported(path + ": a " + std::to_string(init.num_dim) +
                       "-dimensional Exodus II mesh; only 3-dimensional meshes hold tetrahedra");
  // Counts come from the file: before anything is allocated they must fit it. A classic netCDF file
  // stores every value; netCDF-4 (HDF5) may deflate them, by at most 1032:1.
  const uint64_t max_bytes = classic ? file_size : std::min<uint64_t>(file_size, UINT64_MAX / 1032) * 1032;
  const uint64_t value_size = io_ws == 4 ? 4 : 8;
  auto fits = [&](int64_t count, uint64_t bytes_each, const std::string& what) -> Status {
    if (count < 0 || static_cast<uint64_t>(count) > max_bytes / bytes_each)
      return invalidData(path + ": the header announces " + std::to_string(count) + " " + what + ", more than the " +
                         std::to_string(file_size) + "-byte file can hold");
    return Status::ok();
  };
  GTN_RETURN_IF_ERROR(fits(init.num_nodes, 3 * value_size, "nodes"));
  if (init.num_nodes >= int64_t{UINT32_MAX} - 1)
    return unsupported(path + ": " + std::to_string(init.num_nodes) + " nodes; at most 2^32-2 are supported");
  GTN_RETURN_IF_ERROR(fits(init.num_elem_blk, 1, "element blocks"));
  if (init.num_elem_blk > INT32_MAX)  // the Exodus API counts blocks in an int
    return unsupported(path + ": " + std::to_string(init.num_elem_blk) +
                       " element blocks; at most 2^31-1 are supported");

  ImportResult result;
  TetMesh& mesh = result.mesh;
  std::vector<std::string>& warnings = result.report.warnings;
  const size_t num_nodes = static_cast<size_t>(init.num_nodes);
  {
    std::vector<double> xyz[3];
    for (auto& a : xyz) a.resize(num_nodes);
    if (num_nodes > 0 && api.ex_get_coord(exoid, xyz[0].data(), xyz[1].data(), xyz[2].data()) < 0)
      return invalidData(path + ": cannot read the node coordinates (ex_get_coord: " + exodusError(api) + ")");
    mesh.coords.resize(3 * num_nodes);
    for (size_t i = 0; i < num_nodes; ++i)
      for (int c = 0; c < 3; ++c) {
        const double v = xyz[c][i];
        if (!std::isfinite(v))
          return invalidData(path + ": node " + std::to_string(i + 1) + " has a non-finite " + "xyz"[c] +
                             " coordinate");
        mesh.coords[3 * i + c] = v;
      }
    mesh.coord_type = io_ws == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  }

  // Element blocks: the volume ones become cells, the others are counted for a warning.
  const int num_blocks = static_cast<int>(init.num_elem_blk);
  std::vector<int64_t> ids(static_cast<size_t>(num_blocks));
  if (num_blocks > 0 && api.ex_get_ids(exoid, EX_ELEM_BLOCK, ids.data()) < 0)
    return invalidData(path + ": cannot read the element block ids (ex_get_ids: " + exodusError(api) + ")");
  std::vector<Block> blocks(ids.size());
  VtkCells cells;
  std::vector<int32_t> cell_block;
  std::map<std::string, int64_t> skipped;  // element type -> elements skipped
  std::map<std::string, int64_t> higher_order;
  int64_t total_elements = 0;
  // NFACED blocks (polyhedra): the face blocks' faces, read at the first one, how many polyhedra
  // each face bounds so far, and each polyhedron's cell with the end of its face stream.
  FaceTable face_table;
  std::vector<uint8_t> face_uses;
  bool faces_read = false;
  std::vector<std::pair<size_t, int64_t>> polyhedron_ends;
  std::vector<int64_t> polyhedron_points;
  // An NFACED block's elements as VTK polyhedra: each one's face stream (the face count, then each
  // face's node count and nodes) and its distinct nodes as its connectivity.
  auto readPolyhedra = [&](Block& blk, int64_t total_faces, const std::string& where) -> Status {
    GTN_RETURN_IF_ERROR(fits(blk.elements, 4, where + " elements"));
    GTN_RETURN_IF_ERROR(fits(total_faces, 4, where + " element faces"));
    if (cells.types.size() + static_cast<uint64_t>(blk.elements) >= UINT32_MAX)
      return unsupported(path + ": more than 2^32-2 volume elements");
    std::vector<int> per(static_cast<size_t>(blk.elements), 0);
    if (api.ex_get_entity_count_per_polyhedra(exoid, EX_ELEM_BLOCK, blk.id, per.data()) < 0)
      return invalidData(path + ": cannot read the face counts of " + where +
                         " (ex_get_entity_count_per_polyhedra: " + exodusError(api) + ")");
    std::vector<int64_t> conn(static_cast<size_t>(total_faces));
    if (total_faces > 0 && api.ex_get_conn(exoid, EX_ELEM_BLOCK, blk.id, nullptr, nullptr, conn.data()) < 0)
      return invalidData(path + ": cannot read the faces of " + where + " (ex_get_conn: " + exodusError(api) + ")");
    blk.volume = true;
    blk.first_cell = cells.types.size();
    int64_t at = 0;
    for (int64_t e = 0; e < blk.elements; ++e) {
      const std::string element = where + ", element " + std::to_string(e + 1);
      const int n = per[static_cast<size_t>(e)];
      if (n < 4 || n > total_faces - at)
        return invalidData(path + ": " + element + " has " + std::to_string(n) +
                           " faces (at least 4, within the block's " + std::to_string(total_faces) + ")");
      cells.faces.push_back(n);
      polyhedron_points.clear();
      for (int k = 0; k < n; ++k, ++at) {
        const int64_t face = conn[static_cast<size_t>(at)];
        if (face < 1 || static_cast<uint64_t>(face) > face_table.size())
          return invalidData(path + ": " + element + " refers to face " + std::to_string(face) + "; " +
                             (face_table.size() == 0 ? std::string("the file has no faces")
                                                     : "faces are numbered 1 to " + std::to_string(face_table.size())));
        // A face bounds at most two cells; the bound also keeps the face streams within twice the
        // face blocks' size.
        if (face_uses[static_cast<size_t>(face - 1)]++ == 2)
          return invalidData(path + ": " + element + " is the third polyhedron to list face " + std::to_string(face) +
                             "; a face bounds at most two cells");
        const int64_t begin = face_table.offsets[static_cast<size_t>(face - 1)];
        const int64_t end = face_table.offsets[static_cast<size_t>(face)];
        cells.faces.push_back(end - begin);
        cells.faces.insert(cells.faces.end(), face_table.nodes.begin() + begin, face_table.nodes.begin() + end);
        polyhedron_points.insert(polyhedron_points.end(), face_table.nodes.begin() + begin,
                                 face_table.nodes.begin() + end);
      }
      std::sort(polyhedron_points.begin(), polyhedron_points.end());
      polyhedron_points.erase(std::unique(polyhedron_points.begin(), polyhedron_points.end()), polyhedron_points.end());
      cells.connectivity.insert(cells.connectivity.end(), polyhedron_points.begin(), polyhedron_points.end());
      polyhedron_ends.emplace_back(cells.types.size(), static_cast<int64_t>(cells.faces.size()));
      cells.types.push_back(kVtkPolyhedron);
      cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
      cell_block.push_back(static_cast<int32_t>(std::clamp<int64_t>(blk.id, INT32_MIN, INT32_MAX)));
    }
    if (at != total_faces)
      return invalidData(path + ": " + where + ": its elements' face counts add up to " + std::to_string(at) +
                         ", not " + std::to_string(total_faces));
    return Status::ok();
  };
  for (size_t b = 0; b < blocks.size(); ++b) {
    Block& blk = blocks[b];
    blk.id = ids[b];
    ex_block param{};
    param.id = blk.id;
    param.type = EX_ELEM_BLOCK;
    if (api.ex_get_block_param(exoid, &param) < 0)
      return invalidData(path + ": cannot read element block " + std::to_string(blk.id) +
                         " (ex_get_block_param: " + exodusError(api) + ")");
    param.topology[MAX_STR_LENGTH] = '\0';
    blk.type = trimmed(param.topology);
    blk.elements = param.num_entry;
    blk.nodes_per_element = param.num_nodes_per_entry;
    blk.attributes = param.num_attribute;
    const std::string where = "element block " + std::to_string(blk.id) + " (" + blk.type + ")";
    if (blk.elements < 0 || blk.nodes_per_element < 0)
      return invalidData(path + ": " + where + " has a negative count");
    if (blk.elements == 0) continue;
    total_elements += blk.elements;
    if (upper(blk.type).rfind("NFACED", 0) == 0) {
      if (!faces_read) {
        GTN_ASSIGN_OR_RETURN(face_table, readFaceBlocks(api, path, exoid, init.num_face_blk, init.num_nodes, fits));
        face_uses.assign(face_table.size(), 0);
        faces_read = true;
      }
      GTN_RETURN_IF_ERROR(readPolyhedra(blk, param.num_faces_per_entry, where));
      continue;
    }
    if (!volumeType(blk.type, &blk.vt)) {
      skipped[blk.type.empty() ? "untyped" : blk.type] += blk.elements;
      continue;
    }
    if (blk.nodes_per_element < blk.vt.corners)
      return invalidData(path + ": " + where + " has " + std::to_string(blk.nodes_per_element) +
                         " nodes per element; a " + blk.type + " element has at least " +
                         std::to_string(blk.vt.corners));
    // Nodes per element first, so that their product with 4 and with the element count cannot overflow.
    GTN_RETURN_IF_ERROR(fits(blk.nodes_per_element, 4, where + " nodes per element"));
    GTN_RETURN_IF_ERROR(fits(blk.elements, static_cast<uint64_t>(blk.nodes_per_element) * 4, where + " elements"));
    if (cells.types.size() + static_cast<uint64_t>(blk.elements) >= UINT32_MAX)
      return unsupported(path + ": more than 2^32-2 volume elements");
    blk.volume = true;
    blk.first_cell = cells.types.size();
    if (blk.nodes_per_element > blk.vt.corners) higher_order[upper(blk.type)] += blk.elements;
    std::vector<int64_t> conn(static_cast<size_t>(blk.elements * blk.nodes_per_element));
    if (api.ex_get_conn(exoid, EX_ELEM_BLOCK, blk.id, conn.data(), nullptr, nullptr) < 0)
      return invalidData(path + ": cannot read the connectivity of " + where + " (ex_get_conn: " + exodusError(api) +
                         ")");
    cells.types.reserve(cells.types.size() + static_cast<size_t>(blk.elements));
    cells.connectivity.reserve(cells.connectivity.size() + static_cast<size_t>(blk.elements) * blk.vt.corners);
    for (int64_t e = 0; e < blk.elements; ++e) {
      for (int k = 0; k < blk.vt.corners; ++k) {
        const int64_t v = conn[static_cast<size_t>(e * blk.nodes_per_element + k)];
        if (v < 1 || v > init.num_nodes)
          return invalidData(path + ": " + where + ", element " + std::to_string(e + 1) + " refers to node " +
                             std::to_string(v) + "; nodes are numbered 1 to " + std::to_string(init.num_nodes));
        cells.connectivity.push_back(v - 1);
      }
      cells.types.push_back(blk.vt.vtk_type);
      cells.offsets.push_back(static_cast<int64_t>(cells.connectivity.size()));
      cell_block.push_back(static_cast<int32_t>(std::clamp<int64_t>(blk.id, INT32_MIN, INT32_MAX)));
    }
  }
  const size_t num_cells = cells.types.size();
  if (!polyhedron_ends.empty()) {
    // Exodus lists a face once for the two cells it bounds: it winds outward for one of them only.
    cells.faces_shared = true;
    cells.face_offsets.assign(num_cells, -1);
    for (const auto& [cell, end] : polyhedron_ends) cells.face_offsets[cell] = end;
  }
  if (num_cells == 0) {
    std::string what;
    for (const auto& [type, n] : skipped) what += (what.empty() ? "" : ", ") + std::to_string(n) + " " + type;
    return unsupported(path + ": no volume elements (TETRA, HEX, WEDGE, PYRAMID, NFACED)" +
                       (what.empty() ? std::string(": the file has no elements") : ", only " + what));
  }
  if (!skipped.empty()) {
    std::string what;
    int64_t total = 0;
    for (const auto& [type, n] : skipped) {
      what += (what.empty() ? "" : ", ") + std::to_string(n) + " " + type;
      total += n;
    }
    warnings.push_back("skipped " + plural(total, "element", "elements") + " of " + std::to_string(total_elements) +
                       " that are not linear volume elements (" + what +
                       "): only TETRA, HEX, WEDGE, PYRAMID and NFACED blocks become tetrahedra");
  }
  for (const auto& [type, n] : higher_order)
    warnings.push_back(std::to_string(n) + " " + type +
                       " elements: only their corners are kept; their other nodes "
                       "stay as points that no tetrahedron uses");

  // The time step.
  const int64_t steps = api.ex_inquire_int(exoid, EX_INQ_TIME);
  int step = 0;
  if (options.exodus_time_step != 0) {
    if (options.exodus_time_step < 0 || options.exodus_time_step > steps)
      return usageError(path + ": --time-step " + std::to_string(options.exodus_time_step) + ": the file has " +
                        (steps == 0 ? std::string("no time steps") : "time steps 1 to " + std::to_string(steps)));
    step = options.exodus_time_step;
  } else if (steps > 0) {
    step = static_cast<int>(std::min<int64_t>(steps, INT32_MAX));
  }
  const ScalarType value_type = io_ws == 4 ? ScalarType::kFloat32 : ScalarType::kFloat64;
  std::vector<Field> cell_fields;
  {
    Field id("block_id", 1, ScalarType::kInt32, num_cells);
    for (size_t c = 0; c < num_cells; ++c) id.set<int32_t>(c, 0, cell_block[c]);
    cell_fields.push_back(std::move(id));
  }
  int num_node_vars = 0, num_elem_vars = 0, num_global_vars = 0;
  if (api.ex_get_variable_param(exoid, EX_NODAL, &num_node_vars) < 0 ||
      api.ex_get_variable_param(exoid, EX_ELEM_BLOCK, &num_elem_vars) < 0 ||
      api.ex_get_variable_param(exoid, EX_GLOBAL, &num_global_vars) < 0)
    return invalidData(path + ": cannot read the variable counts (ex_get_variable_param: " + exodusError(api) + ")");
  if (num_node_vars < 0 || num_elem_vars < 0 || num_global_vars < 0 || num_node_vars > 100000 ||
      num_elem_vars > 100000 || num_global_vars > 100000)
    return invalidData(path + ": implausible variable counts (" + std::to_string(num_node_vars) + " nodal, " +
                       std::to_string(num_elem_vars) + " element, " + std::to_string(num_global_vars) + " global)");
  if (step == 0 && num_node_vars + num_elem_vars + num_global_vars > 0)
    warnings.push_back("the file defines variables but holds no time step, so no values: no fields read");
  if (step > 0) {
    double time = 0;
    if (api.ex_get_time(exoid, step, &time) < 0)
      return invalidData(path + ": cannot read the time of step " + std::to_string(step) +
                         " (ex_get_time: " + exodusError(api) + ")");
    char text[64];
    std::snprintf(text, sizeof text, "%.17g", time);
    mesh.setMetadata("exodus.time", text);
    mesh.setMetadata("exodus.time_step", std::to_string(step) + " of " + std::to_string(steps));
    if (steps > 1 && options.exodus_time_step == 0)
      warnings.push_back("read time step " + std::to_string(step) + " (time " + text + "), the last of " +
                         std::to_string(steps) + "; --time-step N reads another");

    // Nodal variables.
    GTN_ASSIGN_OR_RETURN(const std::vector<std::string> node_names,
                         readNames(api, path, exoid, EX_NODAL, num_node_vars, name_length, "nodal variables"));
    std::vector<double> values;
    std::vector<NetcdfNodal> stored(node_names.size());
    std::vector<size_t> components(node_names.size(), 1);
    for (size_t v = 0; v < node_names.size(); ++v) {
      stored[v] = netcdfNodal(api, exoid, static_cast<int>(v + 1), num_nodes);
      if (stored[v].components > 1) components[v] = stored[v].components;
    }
    std::vector<std::string> missing;
    for (const VariableGroup& g : groupVariables(node_names, components)) {
      uint32_t width = 0;
      for (int v : g.variables) width += static_cast<uint32_t>(components[static_cast<size_t>(v)]);
      Field f(g.name, width, value_type, num_nodes);
      uint32_t c = 0;
      for (int v : g.variables) {
        const NetcdfNodal& nc = stored[static_cast<size_t>(v)];
        const std::string what =
            "nodal variable '" + node_names[static_cast<size_t>(v)] + "' at time step " + std::to_string(step);
        int rc = 0;
        if (nc.components <= 1) {
          values.assign(num_nodes, 0.0);
          if (num_nodes > 0) rc = api.ex_get_var(exoid, step, EX_NODAL, v + 1, 1, init.num_nodes, values.data());
          if (rc < 0) return invalidData(path + ": cannot read " + what + " (ex_get_var: " + exodusError(api) + ")");
        }
        // Values the Exodus library does not find (rc > 0, a warning) may be where meshio puts them.
        if (nc.components > 1 || rc > 0) {
          if (nc.components == 0 || !readNetcdfNodal(api, exoid, nc, step, num_nodes, &values)) {
            missing.push_back(node_names[static_cast<size_t>(v)]);
            values.assign(num_nodes * std::max<size_t>(nc.components, 1), std::numeric_limits<double>::quiet_NaN());
          }
        }
        const size_t n = std::max<size_t>(nc.components, 1);
        for (size_t i = 0; i < num_nodes; ++i)
          for (size_t k = 0; k < n; ++k) putValue(f, i, c + static_cast<uint32_t>(k), values[i * n + k]);
        c += static_cast<uint32_t>(n);
      }
      mesh.point_fields.push_back(std::move(f));
    }
    if (!missing.empty())
      warnings.push_back("the Exodus library finds no values of the nodal " +
                         std::string(missing.size() == 1 ? "variable " : "variables ") + joinNames(missing) +
                         " at time step " + std::to_string(step) + ": NaN there");

    // Element variables, where the truth table defines them.
    GTN_ASSIGN_OR_RETURN(const std::vector<std::string> elem_names,
                         readNames(api, path, exoid, EX_ELEM_BLOCK, num_elem_vars, name_length, "element variables"));
    std::vector<int> truth(static_cast<size_t>(num_blocks) * static_cast<size_t>(num_elem_vars), 1);
    if (num_blocks > 0 && num_elem_vars > 0 &&
        api.ex_get_truth_table(exoid, EX_ELEM_BLOCK, num_blocks, num_elem_vars, truth.data()) < 0)
      return invalidData(
          path + ": cannot read the element variable truth table (ex_get_truth_table: " + exodusError(api) + ")");
    missing.clear();
    for (const VariableGroup& g : groupVariables(elem_names)) {
      Field f(g.name, static_cast<uint32_t>(g.variables.size()), value_type, num_cells);
      std::vector<int64_t> undefined_blocks;
      for (size_t c = 0; c < g.variables.size(); ++c) {
        const int var = g.variables[c];
        for (size_t b = 0; b < blocks.size(); ++b) {
          const Block& blk = blocks[b];
          if (!blk.volume) continue;
          const size_t n = static_cast<size_t>(blk.elements);
          if (!truth[b * static_cast<size_t>(num_elem_vars) + static_cast<size_t>(var)]) {
            for (size_t e = 0; e < n; ++e)
              putValue(f, blk.first_cell + e, static_cast<uint32_t>(c), std::numeric_limits<double>::quiet_NaN());
            if (c == 0) undefined_blocks.push_back(blk.id);
            continue;
          }
          values.assign(n, 0.0);
          const int rc = api.ex_get_var(exoid, step, EX_ELEM_BLOCK, var + 1, blk.id, blk.elements, values.data());
          if (rc < 0)
            return invalidData(path + ": cannot read element variable '" + elem_names[var] + "' of element block " +
                               std::to_string(blk.id) + " at time step " + std::to_string(step) +
                               " (ex_get_var: " + exodusError(api) + ")");
          if (rc > 0) {  // a warning: no values where the truth table says there are
            values.assign(n, std::numeric_limits<double>::quiet_NaN());
            missing.push_back(elem_names[var] + " (block " + std::to_string(blk.id) + ")");
          }
          for (size_t e = 0; e < n; ++e) putValue(f, blk.first_cell + e, static_cast<uint32_t>(c), values[e]);
        }
      }
      if (!undefined_blocks.empty()) {
        std::string list;
        for (int64_t id : undefined_blocks) list += (list.empty() ? "" : ", ") + std::to_string(id);
        warnings.push_back("element variable '" + g.name + "' is not defined on element " +
                           (undefined_blocks.size() == 1 ? "block " : "blocks ") + list + ": NaN there");
      }
      cell_fields.push_back(std::move(f));
    }
    if (!missing.empty())
      warnings.push_back("the Exodus library finds no values of the element " +
                         std::string(missing.size() == 1 ? "variable " : "variables ") + joinNames(missing) +
                         " at time step " + std::to_string(step) + ": NaN there");

    // Global variables: one value each, kept as metadata.
    GTN_ASSIGN_OR_RETURN(const std::vector<std::string> global_names,
                         readNames(api, path, exoid, EX_GLOBAL, num_global_vars, name_length, "global variables"));
    values.assign(static_cast<size_t>(num_global_vars), 0.0);
    const int global_rc =
        num_global_vars > 0 ? api.ex_get_var(exoid, step, EX_GLOBAL, 1, 0, num_global_vars, values.data()) : 0;
    if (global_rc < 0)
      return invalidData(path + ": cannot read the global variables at time step " + std::to_string(step) +
                         " (ex_get_var: " + exodusError(api) + ")");
    if (global_rc > 0)
      warnings.push_back("the Exodus library finds no values of the global variables " + joinNames(global_names) +
                         " at time step " + std::to_string(step) + ": not kept");
    for (int i = 0; i < (global_rc > 0 ? 0 : num_global_vars); ++i) {
      char text[64];
      std::snprintf(text, sizeof text, "%.17g", values[static_cast<size_t>(i)]);
      mesh.setMetadata("exodus.global." + global_names[static_cast<size_t>(i)], text);
    }
  }

  // What else the file holds and is not read, one warning each.
  {
    int64_t attributes = 0;
    for (const Block& blk : blocks)
      if (blk.volume) attributes += blk.attributes;
    if (attributes > 0)
      warnings.push_back("skipped " + plural(attributes, "element attribute", "element attributes") +
                         " of the volume blocks (not read)");
    const std::pair<int64_t, const char*> others[] = {
        {init.num_node_sets, "node sets"},
        {init.num_side_sets, "side sets"},
        {init.num_elem_sets, "element sets"},
        {init.num_edge_sets, "edge sets"},
        {init.num_face_sets, "face sets"},
        {init.num_edge_blk, "edge blocks"},
        {faces_read ? 0 : init.num_face_blk, "face blocks"},
    };
    for (const auto& [n, what] : others)
      if (n > 0) warnings.push_back("skipped " + std::to_string(n) + " " + what + " (not read)");
    for (const auto& [type, what] : {std::pair{EX_NODE_SET, "node set"}, std::pair{EX_SIDE_SET, "side set"}}) {
      int n = 0;
      if (api.ex_get_variable_param(exoid, type, &n) >= 0 && n > 0)
        warnings.push_back("skipped " + std::to_string(n) + " " + what + " variables (not read)");
    }
  }

  const std::string title = trimmed(init.title);
  if (!title.empty()) mesh.setMetadata("exodus.title", title);
  GTN_RETURN_IF_ERROR(finishVtkImport(path, cells, cell_fields, options, &result));
  mesh.setMetadata("source.format", "exodus");
  GTN_RETURN_IF_ERROR(mesh.checkConsistency(path));
  return result;
}

}  // namespace gtn
