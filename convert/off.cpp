// PLACEHOLDER: replaced by the real importer.
#include "convert/import.h"

namespace gtn {

StatusOr<ImportResult> importOff(const std::string& path, const ImportOptions&) {
  return unsupported("importOff is not implemented yet");
}

}  // namespace gtn
