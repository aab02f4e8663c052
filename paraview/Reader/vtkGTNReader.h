// vtkGTNReader: reads a .gtn file into a vtkUnstructuredGrid of VTK_TETRA cells.
//
// Level or Ratio picks the mesh: Ratio > 0 gives the mesh simplified to that ratio (vertices merged
// away / vertices of level 0), decoded from the finest stored level not beyond it with the remaining
// merges applied on the fly (as `gtn export --ratio`); otherwise the stored level `Level` (0 = the
// lossless mesh). The point and cell array selections name the fields to decode; the others are not
// decoded. Arrays keep their stored type (float32 stays vtkFloatArray, float64 vtkDoubleArray,
// integers their VTK types).
//
// Piece requests: the reader answers a request for piece p of n by a fixed spatial split. It decodes
// the whole level (pieces of the format do not exist yet, so the decode itself is not split), cuts
// the bounding box of the points into n slabs across its longest axis and keeps the
// tetrahedra whose centroid falls in slab p, the cuts between slabs being the quantiles of the
// centroids (about equally many tetrahedra per piece). Every tetrahedron lands in
// exactly one piece. With n > 1 the output carries the file's point and tetrahedron numbers as the
// GlobalIds of point and cell data ("GlobalPointIds", "GlobalCellIds", vtkIdTypeArray), which
// vtkGTNWriter uses to put gathered pieces back together.
#pragma once

#include <string>

#include "vtkGTNModule.h"  // export macro
#include "vtkUnstructuredGridAlgorithm.h"

class vtkDataArraySelection;

class VTKGTN_EXPORT vtkGTNReader : public vtkUnstructuredGridAlgorithm {
 public:
  static vtkGTNReader* New();
  vtkTypeMacro(vtkGTNReader, vtkUnstructuredGridAlgorithm);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);

  // Stored level to read when Ratio is 0 (0 = the lossless mesh).
  vtkSetClampMacro(Level, int, 0, VTK_INT_MAX);
  vtkGetMacro(Level, int);
  // Simplification ratio in [0, 1]; > 0 overrides Level.
  vtkSetClampMacro(Ratio, double, 0.0, 1.0);
  vtkGetMacro(Ratio, double);

  // Levels the file stores: [0, levels - 1] (after RequestInformation; [0, 0] before).
  vtkGetVector2Macro(LevelRange, int);

  vtkGetObjectMacro(PointDataArraySelection, vtkDataArraySelection);
  vtkGetObjectMacro(CellDataArraySelection, vtkDataArraySelection);
  int GetNumberOfPointArrays();
  const char* GetPointArrayName(int index);
  int GetPointArrayStatus(const char* name);
  void SetPointArrayStatus(const char* name, int status);
  int GetNumberOfCellArrays();
  const char* GetCellArrayName(int index);
  int GetCellArrayStatus(const char* name);
  void SetCellArrayStatus(const char* name, int status);

  // Whether `name` starts like a .gtn file (its magic bytes).
  static int CanReadFile(const char* name);

 protected:
  vtkGTNReader();
  ~vtkGTNReader() override;

  int RequestInformation(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;
  int RequestData(vtkInformation*, vtkInformationVector**, vtkInformationVector*) override;

  char* FileName = nullptr;
  int Level = 0;
  double Ratio = 0.0;
  int LevelRange[2] = {0, 0};
  vtkDataArraySelection* PointDataArraySelection;
  vtkDataArraySelection* CellDataArraySelection;

 private:
  vtkGTNReader(const vtkGTNReader&) = delete;
  void operator=(const vtkGTNReader&) = delete;
};
