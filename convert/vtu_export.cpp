// PLACEHOLDER: replaced by the real exporter.
#include "convert/export.h"

namespace gtn {
Status exportVtu(const TetMesh&, const std::string&, const ExportOptions&) {
  return unsupported(".vtu export is not implemented yet");
}
}  // namespace gtn
