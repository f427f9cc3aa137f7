#pragma once
/// \file
/// The version of drape, from the CMake project.

#include <string_view>

namespace drape {

/// "major.minor.patch" of this build.
std::string_view version();

}  // namespace drape
