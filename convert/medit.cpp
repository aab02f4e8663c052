// PLACEHOLDER: replaced by the real importer.
#include "convert/import.h"

namespace gtn {

StatusOr<ImportResult> importMedit(const std::string& path, const ImportOptions&) {
  return unsupported("importMedit is not implemented yet");
}

}  // namespace gtn
