// PLACEHOLDER: replaced by the real importer.
#include "convert/import.h"

namespace gtn {

StatusOr<ImportResult> importVtu(const std::string& path, const ImportOptions&) {
  return unsupported("importVtu is not implemented yet");
}

}  // namespace gtn
