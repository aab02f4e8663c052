// PLACEHOLDER: replaced by the real exporter.
#include "convert/export.h"

namespace gtn {
Status exportTetgen(const TetMesh&, const std::string&) { return unsupported("TetGen export is not implemented yet"); }
}  // namespace gtn
