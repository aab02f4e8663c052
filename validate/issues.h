// The validator's issue registry: every check `gtn validate` performs has one stable SCREAMING_CASE
// code, a severity and a one-line description. Codes are never renamed or reused once released;
// docs/validation-issues.md is generated from this table (`gtn validate --list-issues --markdown`).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace gtn {

enum class Severity : uint8_t { kError = 0, kWarning = 1, kInfo = 2 };
const char* severityName(Severity severity);  // "error", "warning", "info"

// X(enum name, "CODE", severity, layer, "description"). The description is a plural noun phrase so
// that aggregated reports read "412 <description> out of 187395".
#define GTN_VALIDATION_ISSUES(X)                                                                                       \
  /* container: the bytes of the file */                                                                               \
  X(kFileTooSmall, "FILE_TOO_SMALL", kError, "container", "files too small to hold a .gtn header and trailer")         \
  X(kBadMagic, "BAD_MAGIC", kError, "container", "files that do not start with the .gtn magic number")                 \
  X(kUnsupportedVersion, "UNSUPPORTED_VERSION", kError, "container",                                                   \
    "format versions this validator cannot read (newer major version)")                                                \
  X(kChunkFraming, "CHUNK_FRAMING", kError, "container", "chunks whose header or length does not fit the file")        \
  X(kChecksumMismatch, "CHECKSUM_MISMATCH", kError, "container", "chunks or headers whose checksum does not match")    \
  X(kDirectoryMismatch, "DIRECTORY_MISMATCH", kError, "container",                                                     \
    "directory or trailer entries that disagree with the chunks in the file")                                          \
  X(kSizeOutOfBounds, "SIZE_OUT_OF_BOUNDS", kError, "container", "sizes or counts larger than the file can justify")   \
  X(kTrailingBytes, "TRAILING_BYTES", kError, "container", "files with bytes after the end of the container")          \
  X(kReservedBitsSet, "RESERVED_BITS_SET", kError, "container", "reserved fields or flag bits that are not zero")      \
  X(kMalformedContainer, "MALFORMED_CONTAINER", kError, "container",                                                   \
    "container structures the reader rejects for another reason")                                                      \
  X(kUnknownChunk, "UNKNOWN_CHUNK", kInfo, "container", "chunks of a type this validator does not know (skipped)")     \
  /* decoding: every level decodes and agrees with its header */                                                       \
  X(kNoLevels, "NO_LEVELS", kError, "decoding", "files without a level 0")                                             \
  X(kLevelDecodeFailed, "LEVEL_DECODE_FAILED", kError, "decoding", "levels whose coded streams do not decode")         \
  X(kLevelCountMismatch, "LEVEL_COUNT_MISMATCH", kError, "decoding",                                                   \
    "levels whose decoded counts disagree with their header")                                                          \
  X(kBoundaryMismatch, "BOUNDARY_MISMATCH", kError, "decoding",                                                        \
    "levels whose stored boundary surface differs from the boundary of their tetrahedra")                              \
  X(kBoundingBoxMismatch, "BOUNDING_BOX_MISMATCH", kError, "decoding",                                                 \
    "levels whose stored bounding box is not the box of their points, or pieces whose box misses one of their "        \
    "vertices")                                                                                                        \
  /* mesh: each decoded level is a valid tetrahedral mesh */                                                           \
  X(kIndexOutOfRange, "INDEX_OUT_OF_RANGE", kError, "mesh", "tetrahedra referring to a vertex that does not exist")    \
  X(kRepeatedVertex, "REPEATED_VERTEX", kError, "mesh", "tetrahedra using the same vertex twice")                      \
  X(kDuplicateTet, "DUPLICATE_TET", kError, "mesh", "tetrahedra with the same four vertices as another")               \
  X(kNonManifoldFace, "NON_MANIFOLD_FACE", kError, "mesh", "triangular faces shared by three or more tetrahedra")      \
  X(kBoundaryNotClosed, "BOUNDARY_NOT_CLOSED", kError, "mesh",                                                         \
    "boundary edges in an odd number of boundary triangles (the surface has a hole)")                                  \
  X(kBoundaryOrientation, "BOUNDARY_ORIENTATION", kError, "mesh",                                                      \
    "boundary edges used more often in one direction than the other (inconsistent orientation)")                       \
  X(kNonconformingInterface, "NONCONFORMING_INTERFACE", kWarning, "mesh",                                              \
    "boundary triangles that cover the same surface as boundary triangles facing the other way (a "                    \
    "non-conforming interface inside the volume: welded blocks that cut a shared quadrilateral along "                 \
    "different diagonals)")                                                                                            \
  X(kInvertedTet, "INVERTED_TET", kError, "mesh", "inverted tetrahedra (negative volume, exact predicate)")            \
  X(kZeroVolumeTet, "ZERO_VOLUME_TET", kWarning, "mesh", "zero-volume tetrahedra (exact predicate)")                   \
  X(kZeroVolumeTetFromSource, "ZERO_VOLUME_TET_FROM_SOURCE", kInfo, "mesh",                                            \
    "zero-volume tetrahedra the source already had (level 0 equal to --against, or a mip level descending "            \
    "from level 0 by a replayed merge tree)")                                                                          \
  X(kNonFiniteCoordinate, "NON_FINITE_COORDINATE", kError, "mesh", "points with a NaN or infinite coordinate")         \
  X(kNonFiniteValue, "NON_FINITE_VALUE", kWarning, "mesh", "field values that are NaN or infinite")                    \
  X(kUnreferencedPoint, "UNREFERENCED_POINT", kInfo, "mesh", "points no tetrahedron uses")                             \
  X(kFieldSizeMismatch, "FIELD_SIZE_MISMATCH", kError, "mesh", "fields whose item count differs from the mesh")        \
  /* import: a mesh file given instead of a .gtn file, as the importer reads it */                                     \
  X(kImportFailed, "IMPORT_FAILED", kError, "import",                                                                  \
    "mesh files the importer rejects (the message says where and why)")                                                \
  X(kCellsReoriented, "CELLS_REORIENTED", kWarning, "import",                                                          \
    "cells stored with negative orientation (the importer reorients them; left-handed PLOT3D grids are all so)")       \
  X(kCellsDropped, "CELLS_DROPPED", kInfo, "import",                                                                   \
    "cells the importer leaves out (blanked cells, IBLANK holes, other pieces' ghost cells)")                          \
  X(kImportWarning, "IMPORT_WARNING", kInfo, "import", "warnings of the importer (the message says what)")             \
  /* merge tree: the ranked edge collapses of level 0 */                                                               \
  X(kMergeTreeUndecodable, "MERGE_TREE_UNDECODABLE", kError, "merge-tree",                                             \
    "merge-tree chunks that do not decode (the coder rejects the payload)")                                            \
  X(kMergeTreeSize, "MERGE_TREE_SIZE", kError, "merge-tree",                                                           \
    "merge trees whose size differs from level 0's point count")                                                       \
  X(kMergeTreeNotForest, "MERGE_TREE_NOT_FOREST", kError, "merge-tree",                                                \
    "merge-tree parents out of range or on a cycle (the tree is not a forest)")                                        \
  X(kMergeRanksNotPermutation, "MERGE_RANKS_NOT_PERMUTATION", kError, "merge-tree",                                    \
    "merge ranks that are not a permutation of 1..M")                                                                  \
  X(kMergeNotAdjacent, "MERGE_NOT_ADJACENT", kError, "merge-tree",                                                     \
    "merges joining vertices that share no edge when the merge applies (one no tetrahedron uses may merge "            \
    "into any)")                                                                                                       \
  X(kMergeBoundaryIntoInterior, "MERGE_BOUNDARY_INTO_INTERIOR", kError, "merge-tree",                                  \
    "merges of a boundary vertex into an interior vertex or not along a boundary edge")                                \
  X(kMergeInvertsTet, "MERGE_INVERTS_TET", kError, "merge-tree", "merges that invert a tetrahedron")                   \
  X(kMergeFlattensTet, "MERGE_FLATTENS_TET", kError, "merge-tree", "merges that flatten a tetrahedron to zero volume") \
  X(kMergeFlipsBoundary, "MERGE_FLIPS_BOUNDARY", kError, "merge-tree",                                                 \
    "merges that turn a boundary triangle's normal by more than 90 degrees")                                           \
  X(kMergeBreaksManifold, "MERGE_BREAKS_MANIFOLD", kError, "merge-tree",                                               \
    "merges after which a face is shared by three or more tetrahedra")                                                 \
  X(kMergeAnnotationMismatch, "MERGE_ANNOTATION_MISMATCH", kError, "merge-tree",                                       \
    "merges whose stored boundary flag or removed-tetrahedra count disagrees with the replay")                         \
  X(kNoMergeTree, "NO_MERGE_TREE", kInfo, "merge-tree", "files without a merge tree (no simplification data)")         \
  /* levels: stored mip levels agree with level 0 and the merge tree */                                                \
  X(kLevelMergesOutOfRange, "LEVEL_MERGES_OUT_OF_RANGE", kError, "levels",                                             \
    "levels declaring more merges than the merge tree holds, or out of order")                                         \
  X(kLevelMismatch, "LEVEL_MISMATCH", kError, "levels",                                                                \
    "stored levels that differ from level 0 after their number of merges")                                             \
  X(kLevelRatioMismatch, "LEVEL_RATIO_MISMATCH", kError, "levels",                                                     \
    "levels whose declared ratio is not merges / points of level 0")                                                   \
  X(kLevelWithoutMergeTree, "LEVEL_WITHOUT_MERGE_TREE", kError, "levels",                                              \
    "mip levels stored in a file without a merge tree")                                                                \
  /* --against: the file holds exactly the source mesh */                                                              \
  X(kSourceUnreadable, "SOURCE_UNREADABLE", kError, "against", "sources given with --against that cannot be imported") \
  X(kSourceCountMismatch, "SOURCE_COUNT_MISMATCH", kError, "against",                                                  \
    "level 0 point, tetrahedron or field counts that differ from the source")                                          \
  X(kSourceFieldMismatch, "SOURCE_FIELD_MISMATCH", kError, "against",                                                  \
    "fields whose name, type or components differ from the source")                                                    \
  X(kSourceMeshMismatch, "SOURCE_MESH_MISMATCH", kError, "against",                                                    \
    "level 0 tetrahedra (positions, values) that differ from the source up to renumbering")

enum class IssueCode : uint16_t {
#define GTN_ISSUE_ENUM(name, code, severity, layer, description) name,
  GTN_VALIDATION_ISSUES(GTN_ISSUE_ENUM)
#undef GTN_ISSUE_ENUM
};

struct IssueInfo {
  IssueCode id;
  const char* code;  // stable SCREAMING_CASE name
  Severity severity;
  const char* layer;        // container, decoding, import, mesh, merge-tree, levels, against
  const char* description;  // plural noun phrase
};

const IssueInfo& issueInfo(IssueCode code);
std::span<const IssueInfo> allIssues();
// Looks a code up by its SCREAMING_CASE name.
std::optional<IssueCode> issueFromName(const std::string& name);

// The list of every issue, as plain text (one line per code) or as the Markdown page
// docs/validation-issues.md.
std::string issueListText(bool markdown);

}  // namespace gtn
