// vtkGTNWriter: writes a vtkUnstructuredGrid of tetrahedra as .gtn, the way `gtn convert` writes
// (level 0, mip levels and merge trees, every level decoded back and checked before the file is
// committed).
//
// Points keep their precision (float points give float32 coordinates), point and cell arrays their
// type. Negatively oriented tetrahedra are reoriented (as every importer does). Cells other than
// VTK_TETRA are an error naming the first one. Arrays a .gtn field cannot hold (strings) are left out
// with a warning.
//
// Gathered pieces: when the point data carries GlobalIds (vtkGTNReader's pieces do), points with the
// same id are one point (the seams between pieces close) and points are ordered by id; cell GlobalIds
// order the tetrahedra; neither array is written as a field. Cells flagged as duplicate ghosts are
// left out. Under MPI, ParaView's writer proxy gathers the pieces to rank 0, which writes one file.
#pragma once

#include "vtkGTNModule.h"  // export macro
#include "vtkWriter.h"

class VTKGTN_EXPORT vtkGTNWriter : public vtkWriter {
 public:
  static vtkGTNWriter* New();
  vtkTypeMacro(vtkGTNWriter, vtkWriter);
  void PrintSelf(ostream& os, vtkIndent indent) override;

  vtkSetStringMacro(FileName);
  vtkGetStringMacro(FileName);

  // Mip levels beyond level 0: -1 = automatic (as `gtn convert`), 0 = none.
  vtkSetClampMacro(Levels, int, -1, 62);
  vtkGetMacro(Levels, int);
  // Store the merge trees (on-the-fly simplification to any ratio).
  vtkSetMacro(MergeTree, bool);
  vtkGetMacro(MergeTree, bool);
  vtkBooleanMacro(MergeTree, bool);

 protected:
  vtkGTNWriter();
  ~vtkGTNWriter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  void WriteData() override;

  char* FileName = nullptr;
  int Levels = -1;
  bool MergeTree = true;

 private:
  vtkGTNWriter(const vtkGTNWriter&) = delete;
  void operator=(const vtkGTNWriter&) = delete;
};
