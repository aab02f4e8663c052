#include "vtkGTNReader.h"

#include <algorithm>
#include <cstring>
#include <memory>
#include <vector>

#include "vtkCellArray.h"
#include "vtkCellData.h"
#include "vtkCommand.h"
#include "vtkDataArraySelection.h"
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

  // The piece's tetrahedra and the points they use, in the file's order.
  std::vector<uint32_t> tets;
  std::vector<int64_t> new_id(mesh.numPoints(), -1);
  std::vector<uint32_t> points;
  if (pieces == 1) {
    tets.resize(mesh.numTets());
    for (size_t t = 0; t < tets.size(); ++t) tets[t] = static_cast<uint32_t>(t);
    points.resize(mesh.numPoints());
    for (size_t p = 0; p < points.size(); ++p) new_id[p] = static_cast<int64_t>(p), points[p] = static_cast<uint32_t>(p);
  } else {
    tets = tetsOfPiece(mesh, piece, pieces);
    std::vector<char> used(mesh.numPoints(), 0);
    for (uint32_t t : tets)
      for (uint32_t v : mesh.tets[t]) used[v] = 1;
    for (size_t p = 0; p < used.size(); ++p)
      if (used[p]) {
        new_id[p] = static_cast<int64_t>(points.size());
        points.push_back(static_cast<uint32_t>(p));
      }
  }

  vtkNew<vtkPoints> vpoints;
  const bool float_coords = mesh.coord_type == gtn::ScalarType::kFloat32;
  vpoints->SetDataType(float_coords ? VTK_FLOAT : VTK_DOUBLE);
  vpoints->SetNumberOfPoints(static_cast<vtkIdType>(points.size()));
  for (size_t i = 0; i < points.size(); ++i) vpoints->SetPoint(static_cast<vtkIdType>(i), mesh.point(points[i]));
  output->SetPoints(vpoints);

  vtkNew<vtkIdTypeArray> offsets, connectivity;
  offsets->SetNumberOfValues(static_cast<vtkIdType>(tets.size() + 1));
  connectivity->SetNumberOfValues(static_cast<vtkIdType>(4 * tets.size()));
  for (size_t i = 0; i < tets.size(); ++i) {
    offsets->SetValue(static_cast<vtkIdType>(i), static_cast<vtkIdType>(4 * i));
    for (int k = 0; k < 4; ++k) connectivity->SetValue(static_cast<vtkIdType>(4 * i + k), new_id[mesh.tets[tets[i]][k]]);
  }
  offsets->SetValue(static_cast<vtkIdType>(tets.size()), static_cast<vtkIdType>(4 * tets.size()));
  vtkNew<vtkCellArray> cells;
  cells->SetData(offsets, connectivity);
  output->SetCells(VTK_TETRA, cells);

  for (const gtn::Field& f : mesh.point_fields) output->GetPointData()->AddArray(vtkgtn::toVtkArray(f, points));
  for (const gtn::Field& f : mesh.cell_fields) output->GetCellData()->AddArray(vtkgtn::toVtkArray(f, tets));
  if (pieces > 1) {
    vtkNew<vtkIdTypeArray> point_ids, cell_ids;
    point_ids->SetName("GlobalPointIds");
    point_ids->SetNumberOfValues(static_cast<vtkIdType>(points.size()));
    for (size_t i = 0; i < points.size(); ++i) point_ids->SetValue(static_cast<vtkIdType>(i), points[i]);
    cell_ids->SetName("GlobalCellIds");
    cell_ids->SetNumberOfValues(static_cast<vtkIdType>(tets.size()));
    for (size_t i = 0; i < tets.size(); ++i) cell_ids->SetValue(static_cast<vtkIdType>(i), tets[i]);
    output->GetPointData()->SetGlobalIds(point_ids);
    output->GetCellData()->SetGlobalIds(cell_ids);
  }
  return 1;
}
