# The installed package (issue 11): what `cmake --install <build> --prefix P` writes
# besides the libraries, headers and command (engine/CMakeLists.txt, host/CMakeLists.txt):
#
#   P/lib/cmake/kodawari/kodawariConfig.cmake         find_package(kodawari 0.3 CONFIG)
#   P/lib/cmake/kodawari/kodawariConfigVersion.cmake  which requested versions this one satisfies
#   P/lib/cmake/kodawari/kodawariTargets*.cmake       the export set kodawariTargets
#   P/lib/pkgconfig/kodawari.pc                       pkg-config --cflags --libs kodawari
#   P/lib/pkgconfig/kodawari-c.pc                     the C API: pkg-config --cflags --libs kodawari-c
#   P/share/doc/kodawari/                             README.md, CHANGELOG.md, docs/ (the reference)
#
# tests/package/ installs a build into a temporary prefix and builds programs against it.
include(CMakePackageConfigHelpers)

set(KODAWARI_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/kodawari)

install(EXPORT kodawariTargets
  NAMESPACE kodawari::
  DESTINATION ${KODAWARI_CMAKE_INSTALL_DIR})

if(BUILD_SHARED_LIBS)
  set(KODAWARI_PACKAGE_SHARED ON)
else()
  set(KODAWARI_PACKAGE_SHARED OFF)
endif()
configure_package_config_file(${CMAKE_CURRENT_LIST_DIR}/kodawariConfig.cmake.in
  ${PROJECT_BINARY_DIR}/package/kodawariConfig.cmake
  INSTALL_DESTINATION ${KODAWARI_CMAKE_INSTALL_DIR})
# While the version is 0.x, a minor release may break the API (semantic versioning's rule
# for 0.y.z), so find_package(kodawari 0.3) accepts 0.3.x and nothing else: 0.4 must be
# asked for. SameMajorVersion would accept 0.4, 0.5, ... for a request of 0.3. From 1.0
# on, SameMajorVersion is the rule.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(compatibility SameMinorVersion)
else()
  set(compatibility SameMajorVersion)
endif()
write_basic_package_version_file(${PROJECT_BINARY_DIR}/package/kodawariConfigVersion.cmake
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY ${compatibility})
install(FILES
  ${PROJECT_BINARY_DIR}/package/kodawariConfig.cmake
  ${PROJECT_BINARY_DIR}/package/kodawariConfigVersion.cmake
  DESTINATION ${KODAWARI_CMAKE_INSTALL_DIR})

# pkg-config. The prefix is found from the file's own folder (${pcfiledir}), so that the
# file holds wherever the tree is installed: `cmake --install --prefix` chooses the prefix
# after this file is configured.
set(pkgconfig_dir ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
file(RELATIVE_PATH KODAWARI_PC_PREFIX /prefix/${pkgconfig_dir} /prefix)
string(REGEX REPLACE "/$" "" KODAWARI_PC_PREFIX "${KODAWARI_PC_PREFIX}")
foreach(dir LIBDIR INCLUDEDIR)
  if(IS_ABSOLUTE ${CMAKE_INSTALL_${dir}})
    set(KODAWARI_PC_${dir} ${CMAKE_INSTALL_${dir}})
  else()
    set(KODAWARI_PC_${dir} "\${prefix}/${CMAKE_INSTALL_${dir}}")
  endif()
endforeach()
# Cflags: the public headers use GLM and name Vulkan types (kodawari/render/renderer.hpp),
# so glm is required and the Vulkan headers come in through Requires.private, whose Cflags
# pkg-config always gives but whose Libs (-lvulkan) only with --static: the library opens
# the Vulkan loader at run time and needs no link to it. A static build's archives need
# their own dependencies at link time, which is what Libs.private and Requires.private
# are: `pkg-config --static --libs kodawari`. A shared build's libraries carry them.
if(BUILD_SHARED_LIBS)
  set(KODAWARI_PC_REQUIRES_PRIVATE "vulkan")
  set(KODAWARI_PC_LIBS_PRIVATE "")
else()
  set(KODAWARI_PC_REQUIRES_PRIVATE "vulkan, tinygltf, nlohmann_json >= 3.10, libhwy, zlib")
  # meshoptimizer (`--compact --meshopt`): Debian's libmeshoptimizer-dev installs a CMake
  # package but no .pc file, so the library itself.
  set(KODAWARI_PC_LIBS_PRIVATE "-lmeshoptimizer -pthread")
  foreach(lib IN LISTS CMAKE_DL_LIBS)
    string(APPEND KODAWARI_PC_LIBS_PRIVATE " -l${lib}")
  endforeach()
endif()
configure_file(${CMAKE_CURRENT_LIST_DIR}/kodawari.pc.in ${PROJECT_BINARY_DIR}/package/kodawari.pc @ONLY)
# The C API has a file of its own: libkodawari.so is always shared and carries its
# dependencies, so `pkg-config --cflags --libs kodawari-c` is all a C program needs to
# build. To run, the loader must find the library: a system prefix is on its path, any
# other needs -Wl,-rpath,$(pkg-config --variable=libdir kodawari-c) or LD_LIBRARY_PATH
# (docs/install.md, "The C API").
configure_file(${CMAKE_CURRENT_LIST_DIR}/kodawari-c.pc.in ${PROJECT_BINARY_DIR}/package/kodawari-c.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/package/kodawari.pc ${PROJECT_BINARY_DIR}/package/kodawari-c.pc
  DESTINATION ${pkgconfig_dir})

install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/CHANGELOG.md
  DESTINATION ${CMAKE_INSTALL_DOCDIR})
# The reference pages the README links to, next to it so that its relative links
# (docs/embedding.md, docs/images/...) resolve in the installed copy too; the scene schema
# among them, for editors.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs DESTINATION ${CMAKE_INSTALL_DOCDIR})
