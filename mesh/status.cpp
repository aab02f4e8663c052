#include "mesh/status.h"

namespace gtn {

int exitCodeFor(StatusCode code) {
  switch (code) {
    case StatusCode::kOk: return 0;
    case StatusCode::kUsage: return 2;
    case StatusCode::kIo: return 3;
    default: return 1;
  }
}

}  // namespace gtn
