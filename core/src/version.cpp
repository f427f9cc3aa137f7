#include "drape/core/version.h"

namespace drape {

std::string_view version() { return DRAPE_VERSION; }

}  // namespace drape
