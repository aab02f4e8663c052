#include "vtkGTNWriter.h"

#include <algorithm>
#include <cstring>
#include <numeric>
#include <string>
#include <unordered_map>
#include <vector>

#include "vtkCellData.h"
#include "vtkDataArray.h"
#include "vtkDataSetAttributes.h"
#include "vtkCellTypes.h"
#include "vtkIdList.h"
#include "vtkInformation.h"
#include "vtkInformationVector.h"
#include "vtkMultiProcessController.h"
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkStreamingDemandDrivenPipeline.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include "convert/import.h"
#include "format/gtn_parts.h"
#include "validate/write_gtn.h"

#include "vtkGTNTypes.h"

vtkStandardNewMacro(vtkGTNWriter);

namespace {

// The arrays of `data` as fields, item i of the field being tuple order[i] of the array; the global
// ids and VTK's ghost flags are not fields.
std::vector<gtn::Field> toFields(vtkDataSetAttributes* data, const std::vector<vtkIdType>& order,
                                 std::vector<std::string>* skipped) {
  std::vector<gtn::Field> fields;
  for (int a = 0; a < data->GetNumberOfArrays(); ++a) {
    vtkAbstractArray* abstract = data->GetAbstractArray(a);
    vtkDataArray* array = vtkDataArray::SafeDownCast(abstract);
    const char* name = abstract->GetName() ? abstract->GetName() : "";
    if (array && (array == data->GetGlobalIds() || std::strcmp(name, vtkDataSetAttributes::GhostArrayName()) == 0))
      continue;
    const auto type = array ? vtkgtn::scalarTypeOf(array->GetDataType()) : std::nullopt;
    if (!type) {
      skipped->push_back(name);
      continue;
    }
    gtn::Field f(name, static_cast<uint32_t>(array->GetNumberOfComponents()), *type, order.size());
    const size_t item_bytes = f.components * f.valueSize();
    const auto* in = static_cast<const uint8_t*>(array->GetVoidPointer(0));
    for (size_t i = 0; i < order.size(); ++i)
      std::memcpy(f.bytes.data() + i * item_bytes, in + static_cast<size_t>(order[i]) * item_bytes, item_bytes);
    fields.push_back(std::move(f));
  }
  return fields;
}

}  // namespace

vtkGTNWriter::vtkGTNWriter() = default;

vtkGTNWriter::~vtkGTNWriter() { this->SetFileName(nullptr); }

void vtkGTNWriter::PrintSelf(ostream& os, vtkIndent indent) {
  this->Superclass::PrintSelf(os, indent);
  os << indent << "FileName: " << (this->FileName ? this->FileName : "(none)") << "\n";
  os << indent << "Levels: " << this->Levels << "\n";
  os << indent << "MergeTree: " << this->MergeTree << "\n";
  os << indent << "KeepInvalid: " << this->KeepInvalid << "\n";
  os << indent << "WriteInParts: " << this->WriteInParts << "\n";
  os << indent << "Piece: " << this->Piece << " of " << this->NumberOfPieces << "\n";
}

int vtkGTNWriter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  return 1;
}

vtkTypeBool vtkGTNWriter::ProcessRequest(vtkInformation* request, vtkInformationVector** inputVector,
                                         vtkInformationVector* outputVector) {
  // Each rank of a parallel write asks for its own piece of the input.
  if (request->Has(vtkStreamingDemandDrivenPipeline::REQUEST_UPDATE_EXTENT()) && this->WriteInParts &&
      this->NumberOfPieces > 1) {
    vtkInformation* in = inputVector[0]->GetInformationObject(0);
    in->Set(vtkStreamingDemandDrivenPipeline::UPDATE_PIECE_NUMBER(), this->Piece);
    in->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_PIECES(), this->NumberOfPieces);
    in->Set(vtkStreamingDemandDrivenPipeline::UPDATE_NUMBER_OF_GHOST_LEVELS(), 0);
    return 1;
  }
  return this->Superclass::ProcessRequest(request, inputVector, outputVector);
}

namespace {

// The input as a TetMesh (points merged by global id, tetrahedra only, reoriented), and each point's
// key across ranks: its global id, or the bits of its coordinates.
gtn::Status toMesh(vtkUnstructuredGrid* grid, const std::string& path, gtn::ImportResult* result,
                   std::vector<gtn::PointKey>* keys, bool* coordinate_keys, std::vector<std::string>* skipped) {
  const vtkIdType num_points = grid->GetNumberOfPoints();
  const vtkIdType num_cells = grid->GetNumberOfCells();

  // Points: one per global id when the input has them (gathered pieces), else the input's points.
  std::vector<vtkIdType> point_order;          // output point i = input point point_order[i]
  std::vector<uint32_t> point_of(num_points);  // input point -> output point
  vtkDataArray* gids = grid->GetPointData()->GetGlobalIds();
  const bool by_id = gids && gids->GetNumberOfTuples() == num_points;
  *coordinate_keys = !by_id;
  if (by_id) {
    std::vector<vtkIdType> by_id_order(num_points);
    std::iota(by_id_order.begin(), by_id_order.end(), 0);
    std::stable_sort(by_id_order.begin(), by_id_order.end(),
                     [&](vtkIdType a, vtkIdType b) { return gids->GetTuple1(a) < gids->GetTuple1(b); });
    for (size_t k = 0; k < by_id_order.size(); ++k) {
      if (k == 0 || gids->GetTuple1(by_id_order[k]) != gids->GetTuple1(by_id_order[k - 1]))
        point_order.push_back(by_id_order[k]);
      point_of[by_id_order[k]] = static_cast<uint32_t>(point_order.size() - 1);
    }
  } else {
    point_order.resize(num_points);
    std::iota(point_order.begin(), point_order.end(), 0);
    std::iota(point_of.begin(), point_of.end(), 0u);
  }

  // Cells: tetrahedra only, duplicate ghosts left out, in cell global id order when there is one.
  vtkUnsignedCharArray* ghosts = grid->GetCellGhostArray();
  std::vector<vtkIdType> cell_order;
  for (vtkIdType c = 0; c < num_cells; ++c) {
    if (ghosts && (ghosts->GetValue(c) & vtkDataSetAttributes::DUPLICATECELL)) continue;
    if (grid->GetCellType(c) != VTK_TETRA)
      return gtn::invalidData(path + ": cell " + std::to_string(c) + " is a " +
                              vtkCellTypes::GetClassNameFromTypeId(grid->GetCellType(c)) +
                              ", not a tetrahedron: .gtn holds tetrahedral meshes (apply Tetrahedralize first)");
    cell_order.push_back(c);
  }
  vtkDataArray* cgids = grid->GetCellData()->GetGlobalIds();
  if (cgids && cgids->GetNumberOfTuples() == num_cells)
    std::stable_sort(cell_order.begin(), cell_order.end(),
                     [&](vtkIdType a, vtkIdType b) { return cgids->GetTuple1(a) < cgids->GetTuple1(b); });

  gtn::TetMesh& mesh = result->mesh;
  mesh.coord_type = grid->GetPoints() && grid->GetPoints()->GetDataType() == VTK_FLOAT ? gtn::ScalarType::kFloat32
                                                                                       : gtn::ScalarType::kFloat64;
  mesh.coords.resize(3 * point_order.size());
  for (size_t i = 0; i < point_order.size(); ++i) grid->GetPoint(point_order[i], &mesh.coords[3 * i]);
  mesh.tets.resize(cell_order.size());
  vtkNew<vtkIdList> ids;
  for (size_t t = 0; t < cell_order.size(); ++t) {
    grid->GetCellPoints(cell_order[t], ids);
    for (int k = 0; k < 4; ++k) mesh.tets[t][k] = point_of[ids->GetId(k)];
  }
  mesh.point_fields = toFields(grid->GetPointData(), point_order, skipped);
  mesh.cell_fields = toFields(grid->GetCellData(), cell_order, skipped);
  if (keys) {
    keys->resize(point_order.size());
    for (size_t i = 0; i < point_order.size(); ++i) {
      gtn::PointKey& k = (*keys)[i];
      if (by_id) {
        k = {static_cast<uint64_t>(gids->GetTuple1(point_order[i])), 0, 0};
      } else {
        for (int j = 0; j < 3; ++j) std::memcpy(&k[j], &mesh.coords[3 * i + j], sizeof(double));
      }
    }
  }
  GTN_RETURN_IF_ERROR(mesh.checkConsistency(path));
  gtn::finishImport(*result);  // reorients negative tetrahedra
  return gtn::Status::ok();
}

// The ranks of a vtkMultiProcessController as the parts of a write (format/gtn_parts.h).
class ControllerExchange : public gtn::PartExchange {
 public:
  explicit ControllerExchange(vtkMultiProcessController* c) : c_(c) {}
  int part() const override { return c_->GetLocalProcessId(); }
  int parts() const override { return c_->GetNumberOfProcesses(); }
  gtn::Status gather(const std::vector<uint8_t>& mine, std::vector<std::vector<uint8_t>>* all) override {
    const int n = parts();
    long length = static_cast<long>(mine.size());
    std::vector<long> lengths(n);
    if (!c_->Gather(&length, lengths.data(), 1, 0)) return gtn::ioError("MPI gather failed");
    std::vector<vtkIdType> counts(n), offsets(n);
    vtkIdType total = 0;
    for (int q = 0; q < n; ++q) {
      counts[q] = lengths[q];
      offsets[q] = total;
      total += lengths[q];
    }
    std::vector<unsigned char> bytes(part() == 0 ? std::max<vtkIdType>(total, 1) : 1);
    static const unsigned char none = 0;
    if (!c_->GatherV(mine.empty() ? &none : mine.data(), bytes.data(), length, counts.data(), offsets.data(), 0))
      return gtn::ioError("MPI gather failed");
    if (part() == 0) {
      all->resize(n);
      for (int q = 0; q < n; ++q) (*all)[q].assign(bytes.begin() + offsets[q], bytes.begin() + offsets[q] + counts[q]);
    }
    return gtn::Status::ok();
  }
  gtn::Status broadcast(std::vector<uint8_t>* bytes) override {
    long length = static_cast<long>(bytes->size());
    if (!c_->Broadcast(&length, 1, 0)) return gtn::ioError("MPI broadcast failed");
    bytes->resize(length);
    if (length > 0 && !c_->Broadcast(bytes->data(), length, 0)) return gtn::ioError("MPI broadcast failed");
    return gtn::Status::ok();
  }

 private:
  vtkMultiProcessController* c_;
};

// One part alone.
class SoloExchange : public gtn::PartExchange {
 public:
  int part() const override { return 0; }
  int parts() const override { return 1; }
  gtn::Status gather(const std::vector<uint8_t>& mine, std::vector<std::vector<uint8_t>>* all) override {
    *all = {mine};
    return gtn::Status::ok();
  }
  gtn::Status broadcast(std::vector<uint8_t>*) override { return gtn::Status::ok(); }
};

}  // namespace

void vtkGTNWriter::WriteData() {
  if (!this->FileName || !*this->FileName) {
    vtkErrorMacro("vtkGTNWriter: no file name");
    return;
  }
  const std::string path = this->FileName;
  vtkUnstructuredGrid* grid = vtkUnstructuredGrid::SafeDownCast(this->GetInput());
  vtkMultiProcessController* controller = vtkMultiProcessController::GetGlobalController();
  const bool parallel = this->WriteInParts && this->NumberOfPieces > 1 && controller &&
                        controller->GetNumberOfProcesses() == this->NumberOfPieces &&
                        controller->GetLocalProcessId() == this->Piece;
  gtn::ImportResult result;
  std::vector<gtn::PointKey> keys;
  bool coordinate_keys = false;
  std::vector<std::string> skipped;
  gtn::Status st = grid ? toMesh(grid, path, &result, this->WriteInParts ? &keys : nullptr, &coordinate_keys, &skipped)
                        : gtn::usageError(path + ": the input is not a vtkUnstructuredGrid");
  for (const std::string& name : skipped)
    vtkWarningMacro(<< path << ": array '" << name << "' is not numeric: not written");
  if (this->WriteInParts) {
    // Every rank codes its own pieces of level 0; rank 0 writes the file (format/gtn_parts.h).
    ControllerExchange ranks(controller);
    SoloExchange solo;
    gtn::GtnWriteOptions wo;
    wo.tool_version = GTN_VERSION_STRING;
    wo.command_line = "vtkGTNWriter";
    st = gtn::writeGtnFromParts(path, result.mesh, keys, coordinate_keys,
                                parallel ? static_cast<gtn::PartExchange&>(ranks) : solo, wo, nullptr, st);
  } else if (st.isOk()) {
    gtn::GtnConvertOptions options;
    options.levels = this->Levels;
    options.merge_tree = this->MergeTree;
    options.keep_invalid = this->KeepInvalid;
    gtn::GtnWriteOptions wo;
    wo.tool_version = GTN_VERSION_STRING;
    wo.command_line = "vtkGTNWriter";
    std::vector<std::string> warnings;
    st = gtn::writeGtnWithLevels(path, result.mesh, options, wo, path, &warnings);
    for (const std::string& w : warnings) vtkWarningMacro(<< w);
  }
  if (!st.isOk()) vtkErrorMacro(<< st.message());
}
