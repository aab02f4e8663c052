// PLACEHOLDER: replaced by the real importer.
#include "convert/import.h"

namespace gtn {

StatusOr<ImportResult> importVtkLegacy(const std::string& path, const ImportOptions&) {
  return unsupported("importVtkLegacy is not implemented yet");
}

}  // namespace gtn
