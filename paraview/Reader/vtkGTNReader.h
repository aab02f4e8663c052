// vtkGTNReader: reads a .gtn file into a vtkUnstructuredGrid of VTK_TETRA cells.
//
// Level or Ratio picks the mesh: Ratio > 0 gives the mesh simplified to that ratio (vertices merged
// away / vertices of level 0), decoded from the finest stored level not beyond it with the remaining
// merges applied on the fly (as `gtn export --ratio`); otherwise the stored level `Level` (0 = the
// lossless mesh). The point and cell array selections name the fields to decode; the others are not
// decoded. Arrays keep their stored type (float32 stays vtkFloatArray, float64 vtkDoubleArray,
// integers their VTK types).
//
// Piece requests (UPDATE_PIECE_NUMBER p of UPDATE_NUMBER_OF_PIECES n, as ParaView sends one per MPI
// rank): a stored level of several file pieces (gtn convert --piece-tets) is split into n contiguous
// runs of its pieces holding about equally many tetrahedra, and request p reads and decodes only the
// pieces of run p (GtnReader::decodeLevelPieces); with n above the number of pieces some requests get
// none and give an empty grid with the same arrays. Seam vertices shared by pieces of two runs appear
// in both outputs with the same global id. The output's field data carries the level's piece table,
// "GTNPieceBounds" (a tuple per piece: xmin, xmax, ymin, ymax, zmin, zmax) and "GTNPieces" (the
// pieces decoded for this request).
// A mesh simplified on the fly (Ratio > 0) and a level stored as one piece are decoded whole on every
// request, and request p keeps slab p: the bounding box of the points is cut across its longest axis
// into n slabs (the cuts being the quantiles of the tetrahedra's centroids, so about equally many
// tetrahedra per slab) and a tetrahedron belongs to the slab of its centroid.
// Either way every tetrahedron lands in exactly one request's output, and with n > 1 the output
// carries the level's point and tetrahedron numbers as the GlobalIds of point and cell data
// ("GlobalPointIds", "GlobalCellIds", vtkIdTypeArray; the numbers a serial read gives the points and
// cells), which vtkGTNWriter uses to put gathered pieces back together.
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

  // The most threads the decode of a stored level's pieces uses (a TBB arena); 0 = TBB's default,
  // every core. With several MPI ranks on one machine, cores / ranks keeps them from oversubscribing.
  vtkSetClampMacro(Threads, int, 0, VTK_INT_MAX);
  vtkGetMacro(Threads, int);

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
  int Threads = 0;
  int LevelRange[2] = {0, 0};
  vtkDataArraySelection* PointDataArraySelection;
  vtkDataArraySelection* CellDataArraySelection;

 private:
  vtkGTNReader(const vtkGTNReader&) = delete;
  void operator=(const vtkGTNReader&) = delete;
};
