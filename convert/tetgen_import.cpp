// PLACEHOLDER: replaced by the real importer.
#include "convert/import.h"

namespace gtn {

StatusOr<ImportResult> importTetgen(const std::string& path, const ImportOptions&) {
  return unsupported("importTetgen is not implemented yet");
}

}  // namespace gtn
