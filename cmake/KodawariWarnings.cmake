# kodawari::warnings: the warning flags every target of the project builds with.
add_library(kodawari_warnings INTERFACE)
add_library(kodawari::warnings ALIAS kodawari_warnings)
target_compile_options(kodawari_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wnull-dereference
    -Wformat=2 -Wimplicit-fallthrough>
  # GCC's -Wdouble-promotion flags the promotions that cost: a float meeting a double in
  # arithmetic, a float passed to a variadic function. Clang's flags every exact widening
  # as well (`const double t = u;`, `double{u}`), 250 of them, which say nothing.
  $<$<CXX_COMPILER_ID:GNU>:-Wdouble-promotion>
  # GCC 12 reports false -Wrestrict positives inside std::string at -O3 (GCC bug 105329).
  $<$<AND:$<CXX_COMPILER_ID:GNU>,$<VERSION_LESS:$<CXX_COMPILER_VERSION>,13>>:-Wno-restrict>
  $<$<BOOL:${KODAWARI_WARNINGS_AS_ERRORS}>:-Werror>)
