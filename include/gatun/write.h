// <gatun/write.h>: writing a Mesh as a .gtn file with mip levels and merge trees.
// Part of the Gatun API; <gatun/gatun.h> includes every part and says how errors, ownership and
// threads work for all of them.
#pragma once

#include <string>
#include <vector>

#include "gatun/mesh.h"
#include "gatun/result.h"

namespace gatun {

/*-************************************
 *  Writing .gtn files
 **************************************/

/*! WriteOptions : how write() and convert() store a .gtn file (the options of `gtn convert`).
 *  `levels`: mip levels beyond level 0; -1 = automatic (down to a small mesh, within level_storage),
 *     0 = none.
 *  `merge_tree`: store the merge trees (simplification to any ratio on the fly); false stores level 0
 *     alone (mip levels are stored with the tree they are checked against; levels > 0 is refused).
 *  `level_storage`: automatic levels leave out the coarsest while all levels together would take
 *     more than this multiple of level 0's bytes alone (with its merge tree); 0 = no bound.
 *  `independent_levels`: every level stores all its vertices and the rest of the merge tree, so that
 *     each decodes alone (`gtn convert --independent-levels`); by default a level names the next
 *     coarser level's vertices instead of storing them again (a smaller file).
 *  `verify`: decode every written level back and check it (and each mip level's validity) before the
 *     file is committed; false is faster and skips the guard against encoder or simplifier bugs.
 *  `keep_invalid`: write a mesh that has errors of its own, which validate() then reports on the file
 *     (overlapping tetrahedra, say; `gtn convert --keep-invalid`); by default, where `verify` is set,
 *     such a mesh is refused (kInvalidData naming the errors) and nothing is written.
 *  `simplify_field`, `w_density`, `w_geometry`: the ranking of merges: the point field whose first
 *     component is the density ("" = the first that is not constant, "none" = volume only) and the
 *     weights of the density and boundary geometry errors.
 *  `greedy_ranking`: rank the whole mesh in one queue, every candidate a merge changes ranked again at
 *     once (`gtn convert --greedy-ranking`); by default a changed candidate is ranked again when it
 *     comes to the top of the queue, and large meshes are first ranked in parts, in parallel.
 *  `command_line`: the provenance stored in the file header; "" stores "gatun::write(NAME)" or
 *     "gatun::convert(NAME)", NAME the output's file name without its directory.
 *  `piece_tets`: the most tetrahedra a piece of a level holds (`gtn convert --piece-tets`; at least
 *     4096): levels are stored as pieces that decode in parallel and are read by region apart. */
struct WriteOptions {
  int levels = -1;
  bool merge_tree = true;
  double level_storage = 2.0;
  bool independent_levels = false;
  bool verify = true;
  bool keep_invalid = false;
  std::string simplify_field{};
  double w_density = 1.0;
  double w_geometry = 1.0;
  bool greedy_ranking = false;
  std::string command_line{};
  uint64_t piece_tets = uint64_t{1} << 20;
};

/*! write() : writes `mesh` to `path` as a .gtn file: level 0 (lossless), its mip levels and merge
 *  trees as `options` asks, exactly as `gtn convert` writes an imported mesh (the same meshes and
 *  options give the same bytes, up to the provenance). Tetrahedra are first turned to positive
 *  orientation by exact predicates, as the importers do.
 *  `warnings` (optional) receives what a user should hear about, e.g. "flipped 3 tetrahedra to
 *  positive orientation", or fewer levels than asked because the merge tree stops early.
 *  Errors: kUsage (a tetrahedron referring to a missing point, a field of the wrong size, coordinates
 *  that are not finite or not representable in coord_type), kInvalidData (a mesh the encoder refuses,
 *  "...: cannot be encoded: <reason>"; a mesh with errors of its own, "...: the mesh has errors that
 *  `gtn validate` would report on the file (...)", see keep_invalid), kIo. On failure `path` is left
 *  as it was. */
Error write(const std::string& path, const Mesh& mesh, const WriteOptions& options = {},
            std::vector<std::string>* warnings = nullptr);

}  // namespace gatun
