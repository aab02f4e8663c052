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
#include "vtkNew.h"
#include "vtkObjectFactory.h"
#include "vtkPointData.h"
#include "vtkPoints.h"
#include "vtkUnsignedCharArray.h"
#include "vtkUnstructuredGrid.h"

#include "convert/import.h"
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
}

int vtkGTNWriter::FillInputPortInformation(int, vtkInformation* info) {
  info->Set(vtkAlgorithm::INPUT_REQUIRED_DATA_TYPE(), "vtkUnstructuredGrid");
  return 1;
}

void vtkGTNWriter::WriteData() {
  if (!this->FileName || !*this->FileName) {
    vtkErrorMacro("vtkGTNWriter: no file name");
    return;
  }
  const std::string path = this->FileName;
  vtkUnstructuredGrid* grid = vtkUnstructuredGrid::SafeDownCast(this->GetInput());
  if (!grid) {
    vtkErrorMacro(<< path << ": the input is not a vtkUnstructuredGrid");
    return;
  }
  const vtkIdType num_points = grid->GetNumberOfPoints();
  const vtkIdType num_cells = grid->GetNumberOfCells();

  // Points: one per global id when the input has them (gathered pieces), else the input's points.
  std::vector<vtkIdType> point_order;        // output point i = input point point_order[i]
  std::vector<uint32_t> point_of(num_points);  // input point -> output point
  vtkDataArray* gids = grid->GetPointData()->GetGlobalIds();
  if (gids && gids->GetNumberOfTuples() == num_points) {
    std::vector<vtkIdType> by_id(num_points);
    std::iota(by_id.begin(), by_id.end(), 0);
    std::stable_sort(by_id.begin(), by_id.end(),
                     [&](vtkIdType a, vtkIdType b) { return gids->GetTuple1(a) < gids->GetTuple1(b); });
    for (size_t k = 0; k < by_id.size(); ++k) {
      if (k == 0 || gids->GetTuple1(by_id[k]) != gids->GetTuple1(by_id[k - 1])) point_order.push_back(by_id[k]);
      point_of[by_id[k]] = static_cast<uint32_t>(point_order.size() - 1);
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
    if (grid->GetCellType(c) != VTK_TETRA) {
      vtkErrorMacro(<< path << ": cell " << c << " is a " << vtkCellTypes::GetClassNameFromTypeId(grid->GetCellType(c))
                    << ", not a tetrahedron: .gtn holds tetrahedral meshes (apply Tetrahedralize first)");
      return;
    }
    cell_order.push_back(c);
  }
  vtkDataArray* cgids = grid->GetCellData()->GetGlobalIds();
  if (cgids && cgids->GetNumberOfTuples() == num_cells)
    std::stable_sort(cell_order.begin(), cell_order.end(),
                     [&](vtkIdType a, vtkIdType b) { return cgids->GetTuple1(a) < cgids->GetTuple1(b); });

  gtn::ImportResult result;
  gtn::TetMesh& mesh = result.mesh;
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
  std::vector<std::string> skipped;
  mesh.point_fields = toFields(grid->GetPointData(), point_order, &skipped);
  mesh.cell_fields = toFields(grid->GetCellData(), cell_order, &skipped);
  for (const std::string& name : skipped)
    vtkWarningMacro(<< path << ": array '" << name << "' is not numeric: not written");
  gtn::Status st = mesh.checkConsistency(path);
  if (st.isOk()) {
    gtn::finishImport(result);  // reorients negative tetrahedra
    gtn::GtnConvertOptions options;
    options.levels = this->Levels;
    options.merge_tree = this->MergeTree;
    gtn::GtnWriteOptions wo;
    wo.tool_version = GTN_VERSION_STRING;
    wo.command_line = "vtkGTNWriter";
    std::vector<std::string> warnings;
    st = gtn::writeGtnWithLevels(path, mesh, options, wo, path, &warnings);
    for (const std::string& w : warnings) vtkWarningMacro(<< w);
  }
  if (!st.isOk()) vtkErrorMacro(<< st.message());
}
