#include "convert/medit_cells.h"

#include <algorithm>
#include <iterator>

#include "convert/vtk_common.h"

namespace gtn {

constexpr MeditVolumeKeyword kMeditVolumeKeywords[kMeditVolumeKinds] = {
    {"Tetrahedra", "tetrahedron", 4, kVtkTetra, 4},
    {"Hexahedra", "hexahedron", 8, kVtkHexahedron, 8},
    {"Prisms", "prism", 6, kVtkWedge, 6},
    {"Pyramids", "pyramid", 5, kVtkPyramid, 5},
    // Its corners join the other elements (as VTK tetrahedra), not the Tetrahedra: a solution's
    // SolAtTetrahedra values are the Tetrahedra's.
    {"TetrahedraP2", "P2 tetrahedron", 4, kVtkTetra, 10},
    {"HexahedraQ2", "Q2 hexahedron", 8, kVtkHexahedron, 27},
    {"PrismsP2", "P2 prism", 6, kVtkWedge, 18},
    {"PyramidsP2", "P2 pyramid", 5, kVtkPyramid, 14},
};

static_assert(std::all_of(std::begin(kMeditVolumeKeywords), std::end(kMeditVolumeKeywords),
                          [](const MeditVolumeKeyword& k) { return k.nodes <= kMeditMaxNodes; }));
// The table lists the four linear keywords, then their second-order forms in the same order.
constexpr size_t kMeditLinearKinds = 4;
static_assert(std::all_of(std::begin(kMeditVolumeKeywords), std::begin(kMeditVolumeKeywords) + kMeditLinearKinds,
                          [](const MeditVolumeKeyword& k) {
                            const MeditVolumeKeyword& q = (&k)[kMeditLinearKinds];
                            return k.nodes == k.corners && q.corners == k.corners && q.vtk_type == k.vtk_type &&
                                   q.nodes > q.corners;
                          }));

const MeditVolumeKeyword* secondOrderForm(const MeditVolumeKeyword& linear) {
  const size_t index = static_cast<size_t>(&linear - kMeditVolumeKeywords);
  return index < kMeditLinearKinds ? &kMeditVolumeKeywords[index + kMeditLinearKinds] : nullptr;
}

void MeditCells::addSection(const MeditVolumeKeyword& kw, const std::string& where) {
  const size_t index = static_cast<size_t>(&kw - kMeditVolumeKeywords);
  sections[index] += (section_count[index]++ ? ", " : "") + where;
}

void MeditCells::warnAboutSections(ImportResult* result) const {
  for (size_t i = 0; i < kMeditVolumeKinds; ++i) {
    if (section_count[i] < 2) continue;
    result->report.warnings.push_back(std::to_string(section_count[i]) + " " + kMeditVolumeKeywords[i].name +
                                      " sections (" + sections[i] +
                                      ") read one after the other, as meshio does (libMeshb reads only the last)");
  }
}

void MeditCells::reserve(const MeditVolumeKeyword& kw, size_t n, TetMesh* mesh) {
  if (&kw == &kMeditVolumeKeywords[0]) {
    mesh->tets.reserve(mesh->tets.size() + n);
    tet_refs.reserve(tet_refs.size() + n);
  } else {
    others.types.reserve(others.types.size() + n);
    others.offsets.reserve(others.offsets.size() + n);
    others.connectivity.reserve(others.connectivity.size() + n * kw.corners);
    other_refs.reserve(other_refs.size() + n);
  }
}

void MeditCells::add(const MeditVolumeKeyword& kw, const uint32_t* corners, int32_t ref, TetMesh* mesh) {
  if (&kw == &kMeditVolumeKeywords[0]) {
    mesh->tets.push_back({corners[0], corners[1], corners[2], corners[3]});
    tet_refs.push_back(ref);
    return;
  }
  if (kw.nodes > kw.corners) ++reduced[&kw - kMeditVolumeKeywords];
  for (int k = 0; k < kw.corners; ++k) others.connectivity.push_back(corners[k]);
  others.types.push_back(kw.vtk_type);
  others.offsets.push_back(static_cast<int64_t>(others.connectivity.size()));
  other_refs.push_back(ref);
}

namespace {
constexpr const char* kMeditVolumeNames =
    "Tetrahedra, Hexahedra, Prisms or Pyramids, or their TetrahedraP2, HexahedraQ2, PrismsP2 and PyramidsP2 forms";
}  // namespace

std::string noVolumeElements(const std::string& skipped) {
  return skipped.empty()
             ? "no volume elements (" + std::string(kMeditVolumeNames) + "): a surface mesh is not a volume mesh"
             : "no volume elements it reads (" + std::string(kMeditVolumeNames) + "), only " + skipped +
                   ", which are not read";
}

Status finishMeditImport(const std::string& path, const char* format, MeditCells* cells, const ImportOptions& options,
                         ImportResult* result) {
  TetMesh& mesh = result->mesh;
  for (size_t i = 0; i < kMeditVolumeKinds; ++i) {
    const MeditVolumeKeyword& kw = kMeditVolumeKeywords[i];
    if (cells->reduced[i] == 0) continue;
    result->report.warnings.push_back(std::to_string(cells->reduced[i]) + " " + kw.name + " elements kept by their " +
                                      std::to_string(kw.corners) + " corners; their " +
                                      (kw.vtk_type == kVtkTetra ? "mid-edge" : "other") +
                                      " nodes are kept as unreferenced points");
  }
  const bool tets_only = cells->other_refs.empty();
  if (!tets_only) GTN_RETURN_IF_ERROR(readMeditSolutions(options.medit_solutions, tets_only, result));
  if (tets_only) {
    // Tetrahedra only: they stay as they are, one reference each.
    Field ref("ref", 1, ScalarType::kInt32, cells->tet_refs.size());
    for (size_t t = 0; t < cells->tet_refs.size(); ++t) ref.set<int32_t>(t, 0, cells->tet_refs[t]);
    mesh.cell_fields.push_back(std::move(ref));
    finishImport(*result);
  } else {
    // The tetrahedra join the other elements as VTK cells of their own, first, so that the split
    // (which keeps them unchanged) and the spreading of references treat every element alike.
    VtkCells all;
    const size_t num_tets = mesh.tets.size(), num_others = cells->other_refs.size();
    all.types.reserve(num_tets + num_others);
    all.offsets.reserve(num_tets + num_others + 1);
    all.connectivity.reserve(4 * num_tets + cells->others.connectivity.size());
    for (const Tet& t : mesh.tets) {
      all.types.push_back(kVtkTetra);
      for (int k = 0; k < 4; ++k) all.connectivity.push_back(t[k]);
      all.offsets.push_back(static_cast<int64_t>(all.connectivity.size()));
    }
    for (size_t c = 0; c < num_others; ++c) {
      all.types.push_back(cells->others.types[c]);
      for (int64_t k = cells->others.offsets[c]; k < cells->others.offsets[c + 1]; ++k)
        all.connectivity.push_back(cells->others.connectivity[k]);
      all.offsets.push_back(static_cast<int64_t>(all.connectivity.size()));
    }
    mesh.tets.clear();
    mesh.tets.shrink_to_fit();
    cells->others = VtkCells{};
    Field ref("ref", 1, ScalarType::kInt32, num_tets + num_others);
    for (size_t t = 0; t < num_tets; ++t) ref.set<int32_t>(t, 0, cells->tet_refs[t]);
    for (size_t c = 0; c < num_others; ++c) ref.set<int32_t>(num_tets + c, 0, cells->other_refs[c]);
    GTN_RETURN_IF_ERROR(finishVtkImport(path, all, {ref}, options, result));
  }
  mesh.setMetadata("source.format", format);
  GTN_RETURN_IF_ERROR(mesh.checkConsistency(path));
  if (tets_only) GTN_RETURN_IF_ERROR(readMeditSolutions(options.medit_solutions, tets_only, result));
  return Status::ok();
}

}  // namespace gtn
