#include "vtkGTNReader.h"

#include <algorithm>
#include <cstring>
#include <memory>
#include <vector>

#include <tbb/task_arena.h>

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCommand.h"
#include "vtkDataArraySelection.h"
#include "vtkDoubleArray.h"
#include "vtkFieldData.h"
#include "vtkIdTypeArray.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkSmartPointer.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnstructuredGrid.h"

#include "format/decode_fields.h"
#include "format/gtn_reader.h"
#include "mesh/mesh_stream.h"
#include "simplify/levels.h"

#include "vtkGTNTypes.h"

vtkStandardNewMacro(vtkGTNReader);

namespace {

std::unique_ptr<gtn::GtnReader> openGtn(const char* path, std::string* error) {
  gtn::GtnOpenOptions oo;
  oo.verify = false;  // random access through the directory; every chunk read is still checksummed
  auto reader = gtn::GtnReader::open(path, oo);
  if (!reader.isOk()) {
    *error = reader.status().message();
    return nullptr;
  }
  return std::move(reader).value();
}

// Fills `selection` with `fields`' names, keeping the status of names it already knows.
void announceArrays(vtkDataArraySelection* selection, const std::vector<gtn::FieldDesc>& fields) {
  std::vector<std::pair<std::string, bool>> known;
  for (int i = 0; i < selection->GetNumberOfArrays(); ++i)
    known.emplace_back(selection->GetArrayName(i), selection->GetArraySetting(i) != 0);
  selection->RemoveAllArrays();
  for (const gtn::FieldDesc& f : fields) {
    auto it = std::find_if(known.begin(), known.end(), [&](const auto& k) { return k.first == f.name; });
    selection->AddArray(f.name.c_str(), it == known.end() ? true : it->second);
  }
}

// The tetrahedra of piece `piece` of `pieces`: the bounding box of the points is cut across its
// longest axis into `pieces` slabs holding equally many tetrahedra by centroid (the cuts are the
// centroids' quantiles); a tetrahedron belongs to the slab of its centroid, so to exactly one piece.
std::vector<uint32_t> tetsOfPiece(const gtn::TetMesh& mesh, int piece, int pieces) {
  std::vector<uint32_t> kept;
  if (mesh.numPoints() == 0 || mesh.numTets() == 0) return kept;
  double lo[3], hi[3];
  for (int c = 0; c < 3; ++c) lo[c] = hi[c] = mesh.coords[c];
  for (size_t i = 1; i < mesh.numPoints(); ++i)
    for (int c = 0; c < 3; ++c) {
      lo[c] = std::min(lo[c], mesh.coords[3 * i + c]);
      hi[c] = std::max(hi[c], mesh.coords[3 * i + c]);
    }
  int axis = 0;
  for (int c = 1; c < 3; ++c)
    if (hi[c] - lo[c] > hi[axis] - lo[axis]) axis = c;
  std::vector<double> centroid(mesh.numTets());
  for (size_t t = 0; t < mesh.numTets(); ++t) {
    double sum = 0;
    for (uint32_t v : mesh.tets[t]) sum += mesh.coords[3 * static_cast<size_t>(v) + axis];
    centroid[t] = sum / 4;
  }
  std::vector<double> sorted = centroid, cuts;
  for (int p = 1; p < pieces; ++p) {
    auto kth = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() * p / pieces);
    std::nth_element(sorted.begin(), kth, sorted.end());
    cuts.push_back(*kth);
  }
  std::sort(cuts.begin(), cuts.end());
  for (size_t t = 0; t < centroid.size(); ++t)
    if (std::upper_bound(cuts.begin(), cuts.end(), centroid[t]) - cuts.begin() == piece)
      kept.push_back(static_cast<uint32_t>(t));
  return kept;
}


// The file pieces (of a level's piece table `file_pieces`) that request `share` of `shares` decodes:
// the piece list cut into `shares` contiguous runs of about equally many tetrahedra. Piece i goes to
// the share holding the midpoint of its tetrahedra in the level's order,
// min(shares - 1, floor((2 * before_i + tets_i) * shares / (2 * total))), before_i being the
// tetrahedra of the pieces before it; with more shares than pieces some shares get none.
std::vector<uint32_t> filePiecesOfShare(const std::vector<gtn::PieceInfo>& file_pieces, int share, int shares) {
  uint64_t total = 0;
  for (const gtn::PieceInfo& p : file_pieces) total += p.tets;
  std::vector<uint32_t> chosen;
  uint64_t before = 0;
  for (size_t i = 0; i < file_pieces.size(); ++i) {
    const uint64_t tets = file_pieces[i].tets;
    const unsigned __int128 mid2 = static_cast<unsigned __int128>(2 * before + tets);
    const uint64_t owner =
        total == 0 ? i * static_cast<uint64_t>(shares) / file_pieces.size()
                   : static_cast<uint64_t>(mid2 * static_cast<unsigned>(shares) / (2 * static_cast<unsigned __int128>(total)));
    if (std::min<uint64_t>(owner, static_cast<uint64_t>(shares - 1)) == static_cast<uint64_t>(share))
      chosen.push_back(static_cast<uint32_t>(i));
    before += tets;
  }
  return chosen;
}

// A mesh with no points or tetrahedra carrying the fields of `header` that `fields` selects (empty).
gtn::TetMesh emptyMesh(const gtn::LevelHeader& header, const gtn::DecodeFields& fields) {
  gtn::TetMesh mesh;
  mesh.coord_type = header.coord_type;
  for (size_t f = 0; f < header.point_fields.size(); ++f)
    if (f < fields.point.size() && fields.point[f])
      mesh.point_fields.emplace_back(header.point_fields[f].name, header.point_fields[f].components,
                                     header.point_fields[f].type, 0);
  for (size_t f = 0; f < header.cell_fields.size(); ++f)
    if (f < fields.cell.size() && fields.cell[f])
      mesh.cell_fields.emplace_back(header.cell_fields[f].name, header.cell_fields[f].components,
                                    header.cell_fields[f].type, 0);
  return mesh;
}

// Fills `output` with the tetrahedra `tets` of `mesh` and the points `points` they use (nullptr: all
// of them, in order; `points` increasing). With `global_ids`, the points and cells carry the level's
// numbers as GlobalIds ("GlobalPointIds", "GlobalCellIds"): `global_vertex` / `global_tet` map the
// mesh's indices to them (nullptr or empty: the indices are the level's).
void fillOutput(vtkUnstructuredGrid* output, const gtn::TetMesh& mesh, const std::vector<uint32_t>* points,
                const std::vector<uint32_t>* tets, bool global_ids, const std::vector<uint32_t>* global_vertex,
                const std::vector<uint64_t>* global_tet) {
  const size_t np = points ? points->size() : mesh.numPoints();
  const size_t nt = tets ? tets->size() : mesh.numTets();
  auto point_at = [&](size_t i) -> size_t { return points ? (*points)[i] : i; };
  auto tet_at = [&](size_t i) -> size_t { return tets ? (*tets)[i] : i; };

  vtkNew<vtkPoints> vpoints;
  const bool float_coords = mesh.coord_type == gtn::ScalarType::kFloat32;
  vpoints->SetDataType(float_coords ? VTK_FLOAT : VTK_DOUBLE);
  vpoints->SetNumberOfPoints(static_cast<vtkIdType>(np));
  if (float_coords) {
    auto* out = static_cast<float*>(vpoints->GetVoidPointer(0));
    for (size_t i = 0; i < np; ++i)
      for (int c = 0; c < 3; ++c) out[3 * i + c] = static_cast<float>(mesh.coords[3 * point_at(i) + c]);
  } else {
    auto* out = static_cast<double*>(vpoints->GetVoidPointer(0));
    if (!points && np > 0) std::memcpy(out, mesh.coords.data(), 3 * np * sizeof(double));
    for (size_t i = 0; points && i < np; ++i)
      for (int c = 0; c < 3; ++c) out[3 * i + c] = mesh.coords[3 * point_at(i) + c];
  }
  output->SetPoints(vpoints);

  std::vector<vtkIdType> new_id;
  if (points) {
    new_id.assign(mesh.numPoints(), -1);
    for (size_t i = 0; i < np; ++i) new_id[(*points)[i]] = static_cast<vtkIdType>(i);
  }
  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(static_cast<vtkIdType>(nt + 1));
  connectivity->SetNumberOfValues(static_cast<vtkIdType>(4 * nt));
  vtkIdType* off = offsets->GetPointer(0);
  vtkIdType* conn = connectivity->GetPointer(0);
  for (size_t i = 0; i <= nt; ++i) off[i] = static_cast<vtkIdType>(4 * i);
  for (size_t i = 0; i < nt; ++i)
    for (int k = 0; k < 4; ++k) {
      const uint32_t v = mesh.tets[tet_at(i)][k];
      conn[4 * i + k] = points ? new_id[v] : static_cast<vtkIdType>(v);
    }
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  output->SetCells(VTK_TETRA, cells);

  for (const gtn::Field& f : mesh.point_fields) output->GetPointData()->AddArray(vtkgtn::toVtkArray(f, points));
  for (const gtn::Field& f : mesh.cell_fields) output->GetCellData()->AddArray(vtkgtn::toVtkArray(f, tets));
  if (global_ids) {
    const bool map_points = global_vertex && !global_vertex->empty();
    const bool map_tets = global_tet && !global_tet->empty();
    vtkNew<vtkIdTypeArray> point_ids, cell_ids;
    point_ids->SetName("GlobalPointIds");
    point_ids->SetNumberOfValues(static_cast<vtkIdType>(np));
    for (size_t i = 0; i < np; ++i)
      point_ids->SetValue(static_cast<vtkIdType>(i),
                          static_cast<vtkIdType>(map_points ? (*global_vertex)[point_at(i)] : point_at(i)));
    cell_ids->SetName("GlobalCellIds");
    cell_ids->SetNumberOfValues(static_cast<vtkIdType>(nt));
    for (size_t i = 0; i < nt; ++i)
      cell_ids->SetValue(static_cast<vtkIdType>(i),
                         static_cast<vtkIdType>(map_tets ? (*global_tet)[tet_at(i)] : tet_at(i)));
    output->GetPointData()->SetGlobalIds(point_ids);
    output->GetCellData()->SetGlobalIds(cell_ids);
  }
}

// The level's piece table as field data: "GTNPieceBounds" (one tuple per piece of the level: xmin,
// xmax, ymin, ymax, zmin, zmax of its vertices) and "GTNPieces" (the pieces this output decoded).
void addPieceTable(vtkUnstructuredGrid* output, const std::vector<gtn::PieceInfo>& file_pieces,
                   const std::vector<uint32_t>& chosen) {
  vtkNew<vtkDoubleArray> bounds;
  bounds->SetName("GTNPieceBounds");
  bounds->SetNumberOfComponents(6);
  bounds->SetNumberOfTuples(static_cast<vtkIdType>(file_pieces.size()));
  for (size_t p = 0; p < file_pieces.size(); ++p)
    for (int c = 0; c < 3; ++c) {
      bounds->SetComponent(static_cast<vtkIdType>(p), 2 * c, file_pieces[p].bbox_min[c]);
      bounds->SetComponent(static_cast<vtkIdType>(p), 2 * c + 1, file_pieces[p].bbox_max[c]);
    }
  vtkNew<vtkIdTypeArray> decoded;
  decoded->SetName("GTNPieces");
  decoded->SetNumberOfValues(static_cast<vtkIdType>(chosen.size()));
  for (size_t i = 0; i < chosen.size(); ++i) decoded->SetValue(static_cast<vtkIdType>(i), chosen[i]);
  output->GetFieldData()->AddArray(bounds);
  output->GetFieldData()->AddArray(decoded);
}

}  // namespace

vtkGTNReader::vtkGTNReader()
    : PointDataArraySelection(vtkDataArraySelection::New()), CellDataArraySelection(vtkDataArraySelection::New()) {
  this->SetNumberOfInputPorts(0);
  // A changed selection must re-execute the reader.
  this->PointDataArraySelection->AddObserver(vtkCommand::ModifiedEvent, this, &vtkGTNReader::Modified);
  this->CellDataArraySelection->AddObserver(vtkCommand::ModifiedEvent, this, &vtkGTNReader::Modified);
}

vtkGTNReader::~vtkGTNReader() {
  this->SetFileName(nullptr);
  this->PointDataArraySelection->Delete();
  this->CellDataArraySelection->Delete();
}

void vtkGTNReader::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "Level: " << this->Level << "\n";
  os << indent << "Ratio: " << this->Ratio << "\n";
  os << indent << "Threads: " << this->Threads << "\n";
}

int vtkGTNReader::CanReadFile(const char* name) {
  if (!name) return 0;
  std::string error;
  return openGtn(name, &error) ? 1 : 0;
}

int vtkGTNReader::GetNumberOfPointArrays() { return this->PointDataArraySelection->GetNumberOfArrays(); }
const char* vtkGTNReader::GetPointArrayName(int index) { return this->PointDataArraySelection->GetArrayName(index); }
int vtkGTNReader::GetPointArrayStatus(const char* name) { return this->PointDataArraySelection->ArrayIsEnabled(name); }
void vtkGTNReader::SetPointArrayStatus(const char* name, int status) {
  this->PointDataArraySelection->SetArraySetting(name, status);
}
int vtkGTNReader::GetNumberOfCellArrays() { return this->CellDataArraySelection->GetNumberOfArrays(); }
const char* vtkGTNReader::GetCellArrayName(int index) { return this->CellDataArraySelection->GetArrayName(index); }
int vtkGTNReader::GetCellArrayStatus(const char* name) { return this->CellDataArraySelection->ArrayIsEnabled(name); }
void vtkGTNReader::SetCellArrayStatus(const char* name, int status) {
  this->CellDataArraySelection->SetArraySetting(name, status);
}

int vtkGTNReader::RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector) {
  if (!this->FileName || !*this->FileName) {
    vtkErrorMacro("vtkGTNReader: no file name");
    return 0;
  }
  std::string error;
  auto reader = openGtn(this->FileName, &error);
  if (!reader) {
    vtkErrorMacro(<< error);
    return 0;
  }
  this->LevelRange[0] = 0;
  this->LevelRange[1] = static_cast<int>(reader->levels()) - 1;
  const gtn::LevelHeader& h = reader->level(0).header;
  announceArrays(this->PointDataArraySelection, h.point_fields);
  announceArrays(this->CellDataArraySelection, h.cell_fields);
  outputVector->GetInformationObject(0)->Set(CAN_HANDLE_PIECE_REQUEST(), 1);
  return 1;
}

int vtkGTNReader::RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector* outputVector) {
  vtkInformation* outInfo = outputVector->GetInformationObject(0);
  vtkUnstructuredGrid* output = vtkUnstructuredGrid::GetData(outInfo);
  int piece = 0, pieces = 1;
  if (outInfo->Has(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER())) {
    piece = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER());
    pieces = outInfo->Get(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES());
  }
  if (pieces < 1 || piece < 0 || piece >= pieces) {
    output->Initialize();
    return 1;
  }

  std::string error;
  auto reader = openGtn(this->FileName, &error);
  if (!reader) {
    vtkErrorMacro(<< error);
    return 0;
  }
  gtn::GtnReader& r = *reader;
  const std::string path = this->FileName;
  if (this->Ratio <= 0 && static_cast<size_t>(this->Level) >= r.levels()) {
    vtkErrorMacro(<< path << ": level " << this->Level << ": the file holds " << r.levels() << " level(s), 0 to "
                  << r.levels() - 1);
    return 0;
  }
  const size_t level = this->Ratio > 0 ? 0 : static_cast<size_t>(this->Level);
  std::vector<std::string> names;
  for (int i = 0; i < this->PointDataArraySelection->GetNumberOfArrays(); ++i)
    if (this->PointDataArraySelection->GetArraySetting(i)) names.emplace_back(this->PointDataArraySelection->GetArrayName(i));
  for (int i = 0; i < this->CellDataArraySelection->GetNumberOfArrays(); ++i)
    if (this->CellDataArraySelection->GetArraySetting(i)) names.emplace_back(this->CellDataArraySelection->GetArrayName(i));
  auto selected = gtn::selectDecodeFields(r.level(level).header, names, path, "array selection");
  if (!selected.isOk()) {
    vtkErrorMacro(<< selected.status().message());
    return 0;
  }
  const gtn::DecodeFields fields = std::move(selected).value();
  const std::vector<gtn::PieceInfo>& file_pieces = r.level(level).pieces;

  if (this->Ratio <= 0 && file_pieces.size() > 1) {
    // A stored level of several pieces: this request's share is a run of the file's pieces, and only
    // those are read and decoded.
    const std::vector<uint32_t> chosen = filePiecesOfShare(file_pieces, piece, pieces);
    gtn::DecodedPieces decoded;
    if (chosen.empty()) {
      // More requests than file pieces: this share is empty, with the arrays the others carry.
      decoded.mesh = emptyMesh(r.level(level).header, fields);
    } else {
      // All pieces (one request): the mesh's own numbering is the level's, and no subset is named.
      const bool all = chosen.size() == file_pieces.size();
      tbb::task_arena arena(this->Threads > 0 ? this->Threads : tbb::task_arena::automatic);
      auto got = arena.execute([&] { return r.decodeLevelPieces(level, all ? std::vector<uint32_t>{} : chosen, &fields); });
      if (!got.isOk()) {
        vtkErrorMacro(<< got.status().message());
        return 0;
      }
      decoded = std::move(got).value();
      gtn::dropUndecodedFields(decoded.mesh, fields);
    }
    fillOutput(output, decoded.mesh, nullptr, nullptr, pieces > 1, &decoded.global_vertex, &decoded.global_tet);
    addPieceTable(output, file_pieces, chosen);
    return 1;
  }

  // A simplified mesh (Ratio > 0) or a one-piece level: decoded whole, and a request for piece p of
  // n keeps slab p of n (tetsOfPiece).
  gtn::TetMeshBuilder builder;
  gtn::Status st;
  if (this->Ratio > 0) {
    gtn::StatusOr<uint64_t> merges = gtn::mergesForRatio(r, this->Ratio);
    st = merges.isOk() ? gtn::streamSimplified(r, *merges, builder, nullptr, /*clamp=*/true, &fields) : merges.status();
  } else {
    st = r.decodeLevel(level, builder, nullptr, &fields);
  }
  if (!st.isOk()) {
    vtkErrorMacro(<< st.message());
    return 0;
  }
  gtn::TetMesh& mesh = builder.mesh();
  gtn::dropUndecodedFields(mesh, fields);
  if (pieces == 1) {
    fillOutput(output, mesh, nullptr, nullptr, false, nullptr, nullptr);
    return 1;
  }
  // The piece's tetrahedra and the points they use, in the file's order.
  const std::vector<uint32_t> tets = tetsOfPiece(mesh, piece, pieces);
  std::vector<char> used(mesh.numPoints(), 0);
  for (uint32_t t : tets)
    for (uint32_t v : mesh.tets[t]) used[v] = 1;
  std::vector<uint32_t> points;
  for (size_t p = 0; p < used.size(); ++p)
    if (used[p]) points.push_back(static_cast<uint32_t>(p));
  fillOutput(output, mesh, &points, &tets, true, nullptr, nullptr);
  return 1;
}
