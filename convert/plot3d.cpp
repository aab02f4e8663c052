// PLACEHOLDER: replaced by the real importer.
#include "convert/import.h"

namespace gtn {

StatusOr<ImportResult> importPlot3d(const std::vector<std::string>& inputs, const ImportOptions&) {
  return unsupported("importPlot3d is not implemented yet");
}

}  // namespace gtn
