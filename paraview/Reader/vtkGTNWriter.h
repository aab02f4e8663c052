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
// left out.
//
// Under MPI there are two ways to one file. ParaView's writer proxy GTNWriter gathers the pieces to
// rank 0, which writes the file as serially (levels, merge trees). GTNPartsWriter (WriteInParts on)
// writes in parallel: each rank (ParaView sets Piece and NumberOfPieces to the rank and the rank
// count) asks for its piece of the input and codes its own pieces of level 0, the ranks meet
// through the level's seam table (points shared by ranks, matched by point GlobalIds or else by exact
// coordinates, are stored once), and rank 0 writes the file (format/gtn_parts.h). That file holds level
// 0 alone: Levels and MergeTree are not used (mip levels and merge trees need the whole mesh in one
// place; `gtn convert` of the written file adds them).
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
  // Store a mesh with errors of its own that `gtn validate` reports (overlapping tetrahedra, say), with
  // a warning, rather than refuse it (gtn convert --keep-invalid).
  vtkSetMacro(KeepInvalid, bool);
  vtkGetMacro(KeepInvalid, bool);
  vtkBooleanMacro(KeepInvalid, bool);
  // Write level 0 alone, each rank of the global controller coding its own part (off: the serial
  // writer, levels and merge trees as asked).
  vtkSetMacro(WriteInParts, bool);
  vtkGetMacro(WriteInParts, bool);
  vtkBooleanMacro(WriteInParts, bool);
  // This rank's piece and the number of pieces (ranks) of a write in parts.
  vtkSetMacro(Piece, int);
  vtkGetMacro(Piece, int);
  vtkSetClampMacro(NumberOfPieces, int, 1, VTK_INT_MAX);
  vtkGetMacro(NumberOfPieces, int);

 protected:
  vtkGTNWriter();
  ~vtkGTNWriter() override;

  int FillInputPortInformation(int port, vtkInformation* info) override;
  vtkTypeBool ProcessRequest(vtkInformation* request, vtkInformationVector** inputVector,
                             vtkInformationVector* outputVector) override;
  void WriteData() override;

  char* FileName = nullptr;
  int Levels = -1;
  bool MergeTree = true;
  bool KeepInvalid = false;
  bool WriteInParts = false;
  int Piece = 0;
  int NumberOfPieces = 1;

 private:
  vtkGTNWriter(const vtkGTNWriter&) = delete;
  void operator=(const vtkGTNWriter&) = delete;
};
