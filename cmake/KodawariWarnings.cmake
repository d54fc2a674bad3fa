# kodawari::warnings: the warning flags every target of the project builds with.
add_library(kodawari_warnings INTERFACE)
add_library(kodawari::warnings ALIAS kodawari_warnings)
target_compile_options(kodawari_warnings INTERFACE
  $<$<CXX_COMPILER_ID:GNU,Clang>:-Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wno-sign-conversion
    -Wnon-virtual-dtor -Wold-style-cast -Wcast-align -Woverloaded-virtual -Wnull-dereference
    -Wdouble-promotion -Wformat=2 -Wimplicit-fallthrough>
  $<$<BOOL:${KODAWARI_WARNINGS_AS_ERRORS}>:-Werror>)
