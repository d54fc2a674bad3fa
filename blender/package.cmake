# Makes kodawari_blender.zip (cmake -P, from blender/CMakeLists.txt): the add-on's folder
# kodawari_blender/ with the Python package `kodawari` inside it, libkodawari.so and the
# shared libraries it links that are not part of the C and C++ runtimes (Highway,
# tinygltf, stb), so that the zip alone installs in Blender, with no `cmake --install` and
# no environment variable.
#
#   cmake -DSOURCE=<repo>/blender -DPYTHON_BUILD=<build>/python/kodawari -DLIBRARY=<libkodawari.so>
#         -DLIBRARY_NAME=libkodawari.so.<soversion> -DSTAGE=<build>/blender -DZIP=<build>/kodawari_blender.zip
#         -P package.cmake
set(addon ${STAGE}/kodawari_blender)
file(REMOVE_RECURSE ${addon})
file(MAKE_DIRECTORY ${addon}/kodawari)
file(GLOB addon_files ${SOURCE}/kodawari_blender/*.py)
file(COPY ${addon_files} DESTINATION ${addon})
file(GLOB package_files ${PYTHON_BUILD}/*.py)
file(COPY ${package_files} DESTINATION ${addon}/kodawari)
file(COPY_FILE ${LIBRARY} ${addon}/kodawari/${LIBRARY_NAME})

# What the library loads beyond the runtimes every Blender on this system has.
file(GET_RUNTIME_DEPENDENCIES
  LIBRARIES ${LIBRARY}
  RESOLVED_DEPENDENCIES_VAR dependencies
  UNRESOLVED_DEPENDENCIES_VAR unresolved
  POST_EXCLUDE_REGEXES "/lib(c|m|dl|pthread|rt|stdc\\+\\+|gcc_s)\\.so" "/ld-linux")
if(unresolved)
  message(FATAL_ERROR "kodawari_blender.zip: cannot find ${unresolved}, which ${LIBRARY} needs")
endif()
set(preload "")
foreach(dependency IN LISTS dependencies)
  get_filename_component(name ${dependency} NAME)
  # The SONAME's file: the loader matches a preloaded library by it.
  file(COPY_FILE ${dependency} ${addon}/kodawari/${name} ONLY_IF_DIFFERENT)
  string(APPEND preload "\"${name}\", ")
endforeach()
file(APPEND ${addon}/kodawari/_config.py "PRELOAD = (${preload})\n")

file(REMOVE ${ZIP})
execute_process(COMMAND ${CMAKE_COMMAND} -E tar cf ${ZIP} --format=zip kodawari_blender
  WORKING_DIRECTORY ${STAGE} RESULT_VARIABLE failed)
if(failed)
  message(FATAL_ERROR "kodawari_blender.zip: zip failed")
endif()
