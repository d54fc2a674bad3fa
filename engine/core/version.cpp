// The library's version, compiled in from the generated header.
#include "kodawari/core/version.hpp"

namespace kodawari {

std::string_view version() { return kHeaderVersion; }

}  // namespace kodawari
